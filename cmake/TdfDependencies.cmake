# Every dependency comes from a Debian package (scripts/install-deps.sh installs them).
# Target names and pitfalls: ../shared/design/toolchain-notes.md section 2.
find_package(embree 3 REQUIRED CONFIG)
find_package(TBB REQUIRED CONFIG)
find_package(OpenEXR REQUIRED CONFIG)
find_package(Imath REQUIRED CONFIG)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(CGAL REQUIRED CONFIG)
include(CGAL_Eigen3_support)
find_package(nlohmann_json 3 REQUIRED CONFIG)
find_package(CLI11 REQUIRED CONFIG)
find_package(fmt REQUIRED CONFIG)
find_package(TinyGLTF REQUIRED CONFIG)
find_package(PNG REQUIRED)
find_package(JPEG REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(FFTW3 REQUIRED IMPORTED_TARGET fftw3 fftw3f)

# OpenImageIO is used only by the comparison tool path that wants its idiff semantics; it costs
# ~0.45 s of process start-up (261 shared libraries), so the core library never links it.
find_package(OpenImageIO CONFIG)
if(TARGET OpenImageIO::OpenImageIO)
  # Debian bug: the imported target names a non-existent /usr/include/opencv4.
  foreach(_p INTERFACE_INCLUDE_DIRECTORIES INTERFACE_SYSTEM_INCLUDE_DIRECTORIES)
    get_target_property(_v OpenImageIO::OpenImageIO ${_p})
    if(_v)
      list(FILTER _v EXCLUDE REGEX "opencv4")
      set_target_properties(OpenImageIO::OpenImageIO PROPERTIES ${_p} "${_v}")
    endif()
  endforeach()
endif()

if(TDF_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()
if(TDF_BUILD_BENCH)
  find_package(benchmark REQUIRED CONFIG)
endif()
