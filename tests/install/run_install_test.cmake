# The install test (cmake -P): installs a tridiff build tree into a scratch prefix, checks what
# landed there, then configures, builds and runs tests/install/consumer against that prefix
# only. Fails on the first step that fails.
#   -DBUILD_DIR=<tridiff build tree> -DCONSUMER_DIR=<consumer source> -DWORK_DIR=<scratch>
#   -DCXX_COMPILER=<compiler of the build tree>
#   -DSANITIZER_LINK_FLAGS=<what a program linking the build's libraries needs; may be empty>
#   -DWITH_DISTRIBUTED=<ON if the build has distributed/: then tridiff::distributed is checked>
foreach(variable BUILD_DIR CONSUMER_DIR WORK_DIR CXX_COMPILER)
  if(NOT DEFINED ${variable})
    message(FATAL_ERROR "run_install_test.cmake: -D${variable}=... is required")
  endif()
endforeach()

set(prefix "${WORK_DIR}/prefix")
set(consumer_build "${WORK_DIR}/consumer-build")
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# The consumer is an ordinary project: none of tridiff's own build flags (sanitizers,
# -march=native, -Werror on the library) and nothing from the caller's environment.
foreach(variable CXXFLAGS CPPFLAGS LDFLAGS CMAKE_PREFIX_PATH tridiff_DIR CMAKE_BUILD_TYPE
                 CMAKE_GENERATOR CMAKE_TOOLCHAIN_FILE)
  unset(ENV{${variable}})
endforeach()

function(step description)
  message(STATUS "${description}: ${ARGN}")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE output
                  ERROR_VARIABLE output)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "${description} failed (${result}):\n${output}")
  endif()
  message("${output}")
endfunction()

step("install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")

foreach(file include/tridiff/solvers.hpp include/tridiff/solvers/solve.hpp
             include/tridiff/image/image.hpp include/tridiff/diffusion/adi.hpp
             include/tridiff/blur/blur.hpp include/tridiff/dof/lens.hpp
             include/tridiff/ipf/model.hpp)
  if(NOT EXISTS "${prefix}/${file}")
    message(FATAL_ERROR "not installed: ${prefix}/${file}")
  endif()
endforeach()
if(WITH_DISTRIBUTED AND NOT EXISTS "${prefix}/include/tridiff/distributed/solve.hpp")
  message(FATAL_ERROR "not installed: ${prefix}/include/tridiff/distributed/solve.hpp")
endif()
file(GLOB_RECURSE config "${prefix}/*/tridiffConfig.cmake")
if(NOT config)
  message(FATAL_ERROR "no tridiffConfig.cmake under ${prefix}")
endif()
# tridiff's own build flags (tridiff_build_flags: -march=native, -Werror, sanitizers) stay in
# its build: none may reach the exported targets.
file(GLOB_RECURSE exported "${prefix}/*/tridiffTargets*.cmake")
foreach(file IN LISTS exported)
  file(READ "${file}" text)
  foreach(flag tridiff_build_flags -march -Werror -fsanitize)
    string(FIND "${text}" "${flag}" at)
    if(at GREATER -1)
      message(FATAL_ERROR "the exported targets carry a build flag (${flag}): ${file}")
    endif()
  endforeach()
endforeach()

# The installed libraries carry none of tridiff's build flags. A sanitizer build's libraries
# are instrumented, though, so a program linking them needs the sanitizer runtimes: the only
# flags handed to the consumer, and only at link time.
step("configure consumer" "${CMAKE_COMMAND}" -S "${CONSUMER_DIR}" -B "${consumer_build}"
     "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}" -DCMAKE_BUILD_TYPE=Release
     "-DCMAKE_EXE_LINKER_FLAGS=${SANITIZER_LINK_FLAGS}"
     "-DCMAKE_PREFIX_PATH=${prefix}" "-DWITH_DISTRIBUTED=${WITH_DISTRIBUTED}"
     -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
     -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF)

# find_package must have used the scratch prefix, not the source or build tree.
file(STRINGS "${consumer_build}/CMakeCache.txt" found REGEX "^tridiff_DIR:")
string(FIND "${found}" "${prefix}/" at)
if(NOT at GREATER -1)
  message(FATAL_ERROR "tridiff was found outside the install prefix: ${found}")
endif()

step("build consumer" "${CMAKE_COMMAND}" --build "${consumer_build}")
file(READ "${consumer_build}/consumers.txt" consumers)
foreach(library IN LISTS consumers)
  step("run consumer of tridiff::${library}" "${consumer_build}/consumer_${library}")
endforeach()
