# One place for the project's compile options; never global flags.
# RISE_SANITIZE: "address,undefined" or "thread" for the sanitizer builds
# (`bash run.sh sanitize asan|tsan`, README "Reliability"); every target of
# the project is instrumented, the Debian libraries are not.
set(RISE_SANITIZE "" CACHE STRING "Sanitizers for every target (address,undefined | thread); empty: none")
function(rise_target_options target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wconversion -pedantic)
  if(RISE_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(RISE_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=${RISE_SANITIZE} -fno-omit-frame-pointer)
    if(RISE_SANITIZE MATCHES "undefined")
      # A finding fails the test. Not the vptr check: g++ 12's reports LCM's
      # own typed subscriptions (lcm-cpp-impl.hpp cb_func) as "invalid vptr"
      # and then calls through a null one, in a 10-line program outside the
      # project too, where the same program without it delivers the message.
      target_compile_options(${target} PRIVATE -fno-sanitize-recover=undefined -fno-sanitize=vptr)
      target_link_options(${target} PRIVATE -fno-sanitize=vptr)
    endif()
    target_link_options(${target} PRIVATE -fsanitize=${RISE_SANITIZE})
  endif()
  # The repo root is the include root: #include "sim/world.hpp".
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>)
endfunction()
