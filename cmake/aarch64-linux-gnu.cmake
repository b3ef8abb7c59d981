# Cross-compiling Δ for AArch64 (arm64) on a Debian x86-64 machine: Debian's cross toolchain
# (g++-aarch64-linux-gnu) and the arm64 libraries of multiarch (dpkg --add-architecture arm64),
# with the tests run under qemu-user (scripts/test_aarch64.sh sets it all up).
#   cmake -S . -B build-aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
# Libraries and packages' CMake files from the multiarch folders lib/aarch64-linux-gnu (not the
# x86-64 ones beside them) and the cross toolchain's root; programs from the host.
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
# ctest and gtest_discover_tests run the programs through qemu (no binfmt registration needed).
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64)
# GCC's notes that passing a std::pair changed ABI in GCC 10.1 concern code built by older GCCs
# only (a note, not a warning, printed for every file that returns one).
set(CMAKE_CXX_FLAGS_INIT -Wno-psabi)
