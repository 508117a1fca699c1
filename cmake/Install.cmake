# The installable package: the library (rubdyn::core), its headers, the CLI, and a CMake
# package configuration so that a consumer writes
#   find_package(rubdyn 0.1 CONFIG REQUIRED)
#   target_link_libraries(app PRIVATE rubdyn::core)
# (examples/consumer is such a project; tests/ builds it against an installed copy).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(RUBDYN_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/rubdyn)

install(TARGETS rubdyn_core rubdyn
        EXPORT rubdynTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/rubdyn DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT rubdynTargets NAMESPACE rubdyn:: DESTINATION ${RUBDYN_CMAKE_DIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rubdynConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/rubdynConfig.cmake
                              INSTALL_DESTINATION ${RUBDYN_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rubdynConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/rubdynConfig.cmake ${PROJECT_BINARY_DIR}/rubdynConfigVersion.cmake
        DESTINATION ${RUBDYN_CMAKE_DIR})
