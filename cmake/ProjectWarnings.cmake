# Warnings and sanitizers for project targets only (never for dependencies).
function(rubdyn_target_options target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Werror)
  if(RUBDYN_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
