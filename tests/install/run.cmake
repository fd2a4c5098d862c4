# The install_consumer test (cmake -P): installs the build tree into a scratch
# prefix, checks what was installed, and builds every examples/*/main.c
# against that prefix the ways an outside program would:
#   pkg    cc main.c $(pkg-config --cflags --libs bigstep)         (libbigstep.so)
#   pkg-static  the same with --static, -lbigstep as libbigstep.a   (Libs.private)
#   cmake  find_package(bigstep) + bigstep::bigstep                 (libbigstep.so)
#   cmake-static  bigstep::bigstep_static                           (libbigstep.a)
# Each binary runs from the source dir (data/ paths resolve; the shared ones
# with LD_LIBRARY_PATH = the prefix's lib, the static ones without), must exit
# 0, and must print a line matching every pattern of its expected.txt
# (examples/README.md). Any failure stops the script with FATAL_ERROR.
#
# Variables (set by tests/CMakeLists.txt): BS_SOURCE_DIR, BS_BUILD_DIR,
# BS_WORK_DIR, BS_C_COMPILER, BS_CXX_COMPILER, BS_PKG_CONFIG, BS_GENERATOR,
# BS_VERSION, BS_LIBDIR, BS_INCLUDEDIR, BS_BINDIR, BS_SANITIZE, BS_LSAN_SUPP.
cmake_minimum_required(VERSION 3.18)

function(fail msg)
  message(FATAL_ERROR "install_consumer: ${msg}")
endfunction()

# run(WHAT command...): runs the command, fails with its output if it fails;
# RUN_OUT is its stdout.
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err
                  WORKING_DIRECTORY ${BS_SOURCE_DIR})
  if(NOT _rc EQUAL 0)
    string(JOIN " " _cmd ${ARGN})
    fail("${what} failed (${_rc}):\n  ${_cmd}\n--- stdout\n${_out}--- stderr\n${_err}")
  endif()
  set(RUN_OUT "${_out}" PARENT_SCOPE)
  set(RUN_ERR "${_err}" PARENT_SCOPE)
endfunction()

# next_line(TEXT_VAR LINE_VAR): pops the first line of TEXT_VAR (no lists, so
# that ';' and '[' in patterns or output stay as they are).
macro(next_line _text _line)
  string(FIND "${${_text}}" "\n" _pos)
  if(_pos EQUAL -1)
    set(${_line} "${${_text}}")
    set(${_text} "")
  else()
    string(SUBSTRING "${${_text}}" 0 ${_pos} ${_line})
    math(EXPR _pos "${_pos} + 1")
    string(SUBSTRING "${${_text}}" ${_pos} -1 ${_text})
  endif()
  string(REGEX REPLACE "\r$" "" ${_line} "${${_line}}")
endmacro()

# check_output(WHAT OUTPUT EXPECTED_FILE): every pattern line of the file
# matches at least one line of OUTPUT.
function(check_output what output expected)
  file(READ ${expected} _patterns)
  set(_n 0)
  while(NOT _patterns STREQUAL "")
    next_line(_patterns _pat)
    if(_pat STREQUAL "" OR _pat MATCHES "^#")
      continue()
    endif()
    math(EXPR _n "${_n} + 1")
    set(_rest "${output}")
    set(_found FALSE)
    while(NOT _rest STREQUAL "" AND NOT _found)
      next_line(_rest _line)
      if(_line MATCHES "${_pat}")
        set(_found TRUE)
      endif()
    endwhile()
    if(NOT _found)
      fail("${what}: no line of the output matches '${_pat}' (${expected})\n--- output\n${output}")
    endif()
  endwhile()
  if(_n EQUAL 0)
    fail("${expected} has no pattern")
  endif()
endfunction()

foreach(_v BS_SOURCE_DIR BS_BUILD_DIR BS_WORK_DIR BS_C_COMPILER BS_CXX_COMPILER BS_VERSION BS_LIBDIR
           BS_INCLUDEDIR BS_BINDIR)
  if(NOT ${_v})
    fail("${_v} is not set (run through ctest)")
  endif()
endforeach()
if(NOT BS_PKG_CONFIG OR NOT EXISTS "${BS_PKG_CONFIG}")
  fail("pkg-config not found (apt-get install pkg-config, or bash setup.sh build)")
endif()

set(P ${BS_WORK_DIR}/prefix)
set(LIB ${P}/${BS_LIBDIR})
file(REMOVE_RECURSE ${BS_WORK_DIR})
file(MAKE_DIRECTORY ${BS_WORK_DIR})
if(BS_SANITIZE)
  # A sanitizer build installs instrumented libraries whose link flags carry
  # -fsanitize=address,undefined; the programs run with the suite's leak
  # suppressions (MPI's and Gmsh's own allocations).
  set(ENV{LSAN_OPTIONS} "suppressions=${BS_LSAN_SUPP}")
  message(STATUS "sanitizer build: consumers link the sanitizer runtimes through bigstep.pc / bigstep::*")
endif()

# ---- 1. install, and what was installed ------------------------------------
run("cmake --install" ${CMAKE_COMMAND} --install ${BS_BUILD_DIR} --prefix ${P})

foreach(_f ${LIB}/libbigstep.a ${LIB}/libbigstep.so ${LIB}/pkgconfig/bigstep.pc
           ${LIB}/cmake/bigstep/bigstepConfig.cmake ${LIB}/cmake/bigstep/bigstepConfigVersion.cmake
           ${LIB}/cmake/bigstep/bigstepTargets.cmake ${P}/${BS_INCLUDEDIR}/bigstep/bigstep.h
           ${P}/${BS_BINDIR}/bigstep)
  if(NOT EXISTS ${_f})
    fail("not installed: ${_f}")
  endif()
endforeach()

# Nothing else: no tests, benchmarks, private headers or app files.
file(GLOB_RECURSE _installed LIST_DIRECTORIES false RELATIVE ${P} ${P}/*)
foreach(_f IN LISTS _installed)
  if(NOT _f MATCHES "^${BS_INCLUDEDIR}/bigstep/(bs_[a-z0-9_]+|bigstep)\\.h$"
     AND NOT _f MATCHES "^${BS_LIBDIR}/libbigstep\\.(a|so|so\\.[0-9.]+)$"
     AND NOT _f MATCHES "^${BS_LIBDIR}/pkgconfig/bigstep\\.pc$"
     AND NOT _f MATCHES "^${BS_LIBDIR}/cmake/bigstep/bigstep[A-Za-z-]*\\.cmake$"
     AND NOT _f STREQUAL "${BS_BINDIR}/bigstep")
    fail("unexpected installed file ${_f}")
  endif()
endforeach()
if(EXISTS ${P}/${BS_INCLUDEDIR}/bigstep/bs_shim.h)
  fail("the private header bs_shim.h was installed")
endif()

# No path of the source or build tree in the text files (the prefix itself
# lies in the build tree: it is blanked first), nor in the RUNPATHs.
foreach(_f IN LISTS _installed)
  if(_f MATCHES "\\.(h|pc|cmake)$")
    file(READ ${P}/${_f} _text)
    string(REPLACE "${P}" "<prefix>" _text "${_text}")
    foreach(_tree ${BS_BUILD_DIR} ${BS_SOURCE_DIR})
      string(FIND "${_text}" "${_tree}" _at)
      if(NOT _at EQUAL -1)
        fail("${_f} names the tree ${_tree}")
      endif()
    endforeach()
  endif()
endforeach()
find_program(READELF readelf)
if(READELF)
  foreach(_f ${LIB}/libbigstep.so ${P}/${BS_BINDIR}/bigstep)
    run("readelf -d ${_f}" ${READELF} -d ${_f})
    foreach(_tree ${BS_BUILD_DIR} ${BS_SOURCE_DIR})
      string(FIND "${RUN_OUT}" "${_tree}" _at)
      if(NOT _at EQUAL -1)
        fail("the dynamic section of ${_f} names the tree ${_tree}")
      endif()
    endforeach()
  endforeach()
endif()

# The shared library exports the API and nothing else: every exported
# symbol is a bs_ name, none internal (bs__x, or the shim's bs_shim_x, the
# self-collision's, the hierarchy's: declared in headers not installed).
find_program(NM nm)
if(NM)
  run("nm -D ${LIB}/libbigstep.so" ${NM} -D --defined-only ${LIB}/libbigstep.so)
  string(REPLACE "\n" ";" _syms "${RUN_OUT}")
  set(_n_api 0)
  foreach(_l IN LISTS _syms)
    if(NOT _l MATCHES " [A-Za-z] ([^ @]+)")
      continue()
    endif()
    set(_s ${CMAKE_MATCH_1})
    if(_s MATCHES "^(_init|_fini|_edata|_end|__bss_start)$")
      continue()
    endif()
    if(NOT _s MATCHES "^bs_" OR _s MATCHES "^bs__" OR _s MATCHES "^bs_(shim|bvh|selfcollide|penalty|vecops|sym3|svd)_")
      fail("libbigstep.so exports ${_s}, which is not a name of the public headers")
    endif()
    math(EXPR _n_api "${_n_api} + 1")
  endforeach()
  if(_n_api LESS 100)
    fail("libbigstep.so exports only ${_n_api} bs_ symbols: the version script lost the API")
  endif()
  message(STATUS "libbigstep.so exports ${_n_api} symbols, all of the public headers")
endif()

run("bigstep --version" ${P}/${BS_BINDIR}/bigstep --version)
string(FIND "${RUN_OUT}${RUN_ERR}" "${BS_VERSION}" _at)
if(_at EQUAL -1)
  fail("the installed bigstep --version does not print ${BS_VERSION}:\n${RUN_OUT}${RUN_ERR}")
endif()

# ---- 2. the headers: each alone, and the umbrella, as C and as C++ ---------
file(GLOB _headers RELATIVE ${P}/${BS_INCLUDEDIR}/bigstep ${P}/${BS_INCLUDEDIR}/bigstep/*.h)
file(READ ${P}/${BS_INCLUDEDIR}/bigstep/bigstep.h _umbrella)
file(MAKE_DIRECTORY ${BS_WORK_DIR}/headers)
foreach(_h IN LISTS _headers)
  if(NOT _h STREQUAL "bigstep.h")
    string(FIND "${_umbrella}" "#include \"${_h}\"" _at)
    if(_at EQUAL -1)
      fail("bigstep.h does not include ${_h}")
    endif()
  endif()
  set(_tu ${BS_WORK_DIR}/headers/${_h}.c)
  file(WRITE ${_tu} "#include <bigstep/${_h}>\n")
  run("${_h} as C" ${BS_C_COMPILER} -std=c11 -Wall -Wextra -Werror -fsyntax-only -I${P}/${BS_INCLUDEDIR} ${_tu})
  run("${_h} as C++" ${BS_CXX_COMPILER} -x c++ -std=c++17 -Wall -Wextra -Werror -fsyntax-only
      -I${P}/${BS_INCLUDEDIR} ${_tu})
endforeach()

# ---- 3. the examples -------------------------------------------------------
set(ENV{PKG_CONFIG_PATH} ${LIB}/pkgconfig)
run("pkg-config --cflags --libs bigstep" ${BS_PKG_CONFIG} --cflags --libs bigstep)
string(STRIP "${RUN_OUT}" _pc_shared)
separate_arguments(_pc_shared UNIX_COMMAND "${_pc_shared}")
run("pkg-config --static --cflags --libs bigstep" ${BS_PKG_CONFIG} --static --cflags --libs bigstep)
string(STRIP "${RUN_OUT}" _pc_static)
separate_arguments(_pc_static UNIX_COMMAND "${_pc_static}")
# -lbigstep would pick libbigstep.so next to the .a: name the archive.
list(TRANSFORM _pc_static REPLACE "^-lbigstep$" "${LIB}/libbigstep.a")

file(GLOB _examples LIST_DIRECTORIES true ${BS_SOURCE_DIR}/examples/*)
list(SORT _examples)
set(_count 0)
foreach(_ex IN LISTS _examples)
  if(NOT EXISTS ${_ex}/main.c)
    continue()
  endif()
  get_filename_component(_name ${_ex} NAME)
  if(NOT EXISTS ${_ex}/expected.txt)
    fail("examples/${_name} has a main.c but no expected.txt")
  endif()
  set(_w ${BS_WORK_DIR}/examples/${_name})
  file(MAKE_DIRECTORY ${_w})

  run("examples/${_name}: cc with pkg-config" ${BS_C_COMPILER} ${_ex}/main.c ${_pc_shared} -o ${_w}/pkg)
  run("examples/${_name}: cc with pkg-config --static" ${BS_C_COMPILER} ${_ex}/main.c ${_pc_static}
      -o ${_w}/pkg-static)

  # A project of its own, nothing of this build in sight but the prefix.
  string(MAKE_C_IDENTIFIER "${_name}" _id)
  file(WRITE ${_w}/project/CMakeLists.txt
"cmake_minimum_required(VERSION 3.18)
project(consumer_${_id} C)
find_package(bigstep ${BS_VERSION} REQUIRED)
if(NOT bigstep_DIR STREQUAL \"${LIB}/cmake/bigstep\")
  message(FATAL_ERROR \"found bigstep at \${bigstep_DIR}, not in the test prefix\")
endif()
add_executable(cmake \"${_ex}/main.c\")
target_link_libraries(cmake PRIVATE bigstep::bigstep)
add_executable(cmake-static \"${_ex}/main.c\")
target_link_libraries(cmake-static PRIVATE bigstep::bigstep_static)
set_target_properties(cmake cmake-static PROPERTIES RUNTIME_OUTPUT_DIRECTORY \"${_w}\")
")
  set(_gen)
  if(BS_GENERATOR)
    set(_gen -G ${BS_GENERATOR})
  endif()
  run("examples/${_name}: configure with find_package(bigstep)" ${CMAKE_COMMAND} ${_gen} -S ${_w}/project
      -B ${_w}/project/build -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=${BS_C_COMPILER}
      -DCMAKE_PREFIX_PATH=${P})
  run("examples/${_name}: build with find_package(bigstep)" ${CMAKE_COMMAND} --build ${_w}/project/build)

  foreach(_bin pkg pkg-static cmake cmake-static)
    if(_bin MATCHES "static$")
      unset(ENV{LD_LIBRARY_PATH})
      if(READELF) # linked with the archive, not with libbigstep.so
        run("readelf -d ${_bin}" ${READELF} -d ${_w}/${_bin})
        if(RUN_OUT MATCHES "libbigstep")
          fail("examples/${_name}: ${_bin} needs libbigstep.so")
        endif()
      endif()
    else()
      set(ENV{LD_LIBRARY_PATH} ${LIB})
    endif()
    run("examples/${_name}: ${_bin}" ${_w}/${_bin})
    check_output("examples/${_name}: ${_bin}" "${RUN_OUT}" ${_ex}/expected.txt)
  endforeach()
  unset(ENV{LD_LIBRARY_PATH})
  message(STATUS "examples/${_name}: pkg, pkg-static, cmake, cmake-static: output matches expected.txt")
  math(EXPR _count "${_count} + 1")
endforeach()
if(_count EQUAL 0)
  fail("no examples/*/main.c")
endif()
message(STATUS "install_consumer: ${_count} example(s) built and checked against ${P}")
