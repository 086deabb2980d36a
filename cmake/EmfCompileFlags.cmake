# Warnings as errors for our own code, and the sanitizer switch (EMF_SANITIZE).
# Third-party headers are included as SYSTEM so their warnings do not fail our build.

function(emf_set_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Werror -Wshadow -Wnon-virtual-dtor
                               -Wold-style-cast -Wcast-align -Woverloaded-virtual
                               -Wno-error=deprecated-declarations>
    $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra -Wpedantic -Werror>)
  # GCC 12's -Wmaybe-uninitialized fires inside libstdc++'s std::regex when AddressSanitizer's
  # instrumentation is optimised (-O1, the test command's ASan build): a false positive in
  # library code. The release build keeps the warning as an error.
  if(EMF_SANITIZE MATCHES "address" AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wno-maybe-uninitialized)
  endif()
endfunction()

# Floating point as written, on every CPU: GCC contracts a*b+c into one fused multiply-add
# wherever the target has one (aarch64 always does, x86-64 only with -mfma), and the CPU
# references of the kernels must compute the same rounding on arm64 as on x86-64.
add_compile_options($<$<COMPILE_LANGUAGE:CXX,C>:-ffp-contract=off>)

# Debug and RelWithDebInfo carry line tables only (-g1, after CMake's -g): backtraces, perf and
# sanitizer reports keep file:line, and the build is about a third faster on two cores than with
# full debug info (locals and types). EMF_FULL_DEBUG_INFO=ON keeps CMake's -g for a debugger.
if(NOT EMF_FULL_DEBUG_INFO AND CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  add_compile_options($<$<AND:$<COMPILE_LANGUAGE:CXX,C>,$<CONFIG:Debug,RelWithDebInfo>>:-g1>)
endif()

set(EMF_SANITIZE_FLAGS "")
if(EMF_SANITIZE)
  if(NOT EMF_SANITIZE MATCHES "^(address,undefined|undefined,address|address|undefined|thread)$")
    message(FATAL_ERROR "EMF_SANITIZE='${EMF_SANITIZE}': use 'address,undefined' or 'thread'")
  endif()
  set(EMF_SANITIZE_FLAGS -fsanitize=${EMF_SANITIZE} -fno-omit-frame-pointer)
  if(EMF_SANITIZE MATCHES "undefined")
    list(APPEND EMF_SANITIZE_FLAGS -fno-sanitize-recover=undefined)
  endif()
  # Sanitize everything we compile (tests and tools included) so runtime libraries match.
  add_compile_options(${EMF_SANITIZE_FLAGS})
  add_link_options(${EMF_SANITIZE_FLAGS})
endif()
