# Every dependency comes from Debian packages; scripts/bootstrap installs them.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json REQUIRED)
find_package(Threads REQUIRED)
# libpcap (Velodyne .pcap/.pcapng sources); Debian ships a pkg-config file, no CMake config.
find_package(PkgConfig REQUIRED)
pkg_check_modules(PCAP REQUIRED IMPORTED_TARGET libpcap)
pkg_check_modules(SQLITE3 REQUIRED IMPORTED_TARGET sqlite3)  # ROS 2 bags (.db3)
pkg_check_modules(LZ4 REQUIRED IMPORTED_TARGET liblz4)  # ROS 1 bag and MCAP chunks (lz4 frames)
pkg_check_modules(ZSTD REQUIRED IMPORTED_TARGET libzstd)  # MCAP chunks
find_package(BZip2 REQUIRED)  # ROS 1 bag chunks (bz2)
if(RINGTRACK_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(RINGTRACK_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()
