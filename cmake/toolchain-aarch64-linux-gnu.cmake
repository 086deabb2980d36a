# Cross build for arm64 (aarch64) on a Debian x86-64 machine (scripts/test_arm64.sh): the cross
# compiler of g++-aarch64-linux-gnu, the arm64 libraries in a sysroot unpacked from Debian's
# arm64 packages (EMF_ARM64_SYSROOT), the test programs run under qemu-user.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES EMF_ARM64_SYSROOT)
if(NOT EMF_ARM64_SYSROOT OR NOT EXISTS "${EMF_ARM64_SYSROOT}/usr/include")
  message(FATAL_ERROR "EMF_ARM64_SYSROOT='${EMF_ARM64_SYSROOT}' is not an arm64 sysroot: "
                      "scripts/test_arm64.sh makes one")
endif()
set(CMAKE_SYSROOT "${EMF_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH "${EMF_ARM64_SYSROOT}")
# Libraries, headers and CMake packages from the sysroot; programs (pkg-config) from the host.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${EMF_ARM64_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${EMF_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${EMF_ARM64_SYSROOT}/usr/share/pkgconfig")
# Test programs run through the emulator, which finds the arm64 loader and libraries in the
# sysroot (gtest_discover_tests lists the tests with it too).
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L "${EMF_ARM64_SYSROOT}")
