# Warnings and sanitizers for project targets only (never for dependencies).
function(rubdyn_target_options target)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
  if(RUBDYN_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(RUBDYN_SANITIZE)
    # -Wmaybe-uninitialized gives false positives under the sanitizers' instrumentation with
    # g++ 12 (in libstdc++'s <regex>, pulled in by Catch2): it stays on in the normal build.
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined
                                             -Wno-maybe-uninitialized)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
