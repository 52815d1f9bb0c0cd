# FFTW in single precision with its OpenMP threads (blur method "fft"), as imported targets
# FFTW3f::fftw3f and FFTW3f::fftw3f_omp: Debian's libfftw3-dev ships no CMake package for it.
# Included by blur/CMakeLists.txt and by the installed tridiffConfig.cmake (a static
# tridiff::blur needs them at link time). Sets TRIDIFF_FFTW3F_FOUND; needs OpenMP::OpenMP_CXX.
find_library(TRIDIFF_FFTW3F fftw3f)
find_library(TRIDIFF_FFTW3F_OMP fftw3f_omp)
if(TRIDIFF_FFTW3F AND TRIDIFF_FFTW3F_OMP)
  set(TRIDIFF_FFTW3F_FOUND TRUE)
  if(NOT TARGET FFTW3f::fftw3f)
    add_library(FFTW3f::fftw3f UNKNOWN IMPORTED)
    set_target_properties(FFTW3f::fftw3f PROPERTIES IMPORTED_LOCATION "${TRIDIFF_FFTW3F}")
  endif()
  if(NOT TARGET FFTW3f::fftw3f_omp)
    add_library(FFTW3f::fftw3f_omp UNKNOWN IMPORTED)
    set_target_properties(FFTW3f::fftw3f_omp PROPERTIES
      IMPORTED_LOCATION "${TRIDIFF_FFTW3F_OMP}"
      INTERFACE_LINK_LIBRARIES "FFTW3f::fftw3f;OpenMP::OpenMP_CXX")
  endif()
else()
  set(TRIDIFF_FFTW3F_FOUND FALSE)
endif()
