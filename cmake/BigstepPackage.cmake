# bigstep as a library for other programs. `cmake --install build --prefix P`
# writes
#   P/lib/libbigstep.a, P/lib/libbigstep.so   every folder library of
#       BS_LIBRARIES (bs_base ... bs_scene, bs_sim, bs_runfolder, bs_study), archived
#       and linked from the objects those libraries already compiled
#   P/include/bigstep/    the public headers, flat, and the umbrella bigstep.h
#   P/lib/pkgconfig/bigstep.pc
#   P/lib/cmake/bigstep/  bigstep::bigstep (shared), bigstep::bigstep_static
#   P/bin/bigstep
# Included at the end of the top CMakeLists.txt, once every folder is known.
# tests/install/run.cmake installs into a scratch prefix and builds
# examples/*/main.c against it.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# The installed headers: bigstep's public API, listed here and nowhere else.
# The API proper: base (errors, limits), scene, sim (the simulation, its
# fields, forces, QoIs, memory estimate), terms for user energy terms,
# mesh, runfolder (with the audit of saved frames), study, and the sampling
# of a surface into a level set. With them the headers whose types they expose:
# materials, the fem and the step options (physics/), the block matrix user
# terms assemble into and the minimizer's options (solver/), obstacles and
# level sets (collision/). Every other header is internal: not installed,
# its functions not exported (the version script below); headers not named
# bs_*.h are private by their name.
set(BS_PUBLIC_HEADERS
    base/bs_base.h base/bs_limits.h
    scene/bs_scene.h scene/bs_field_names.h
    sim/bs_sim.h sim/bs_fields.h sim/bs_forces.h sim/bs_qoi.h sim/bs_memory.h
    physics/bs_terms.h physics/bs_material.h physics/bs_fem.h physics/bs_step.h
    solver/bs_bsr.h solver/bs_minimize.h solver/bs_linsolve.h solver/bs_amg.h
    collision/bs_obstacles.h collision/bs_levelset.h
    mesh/bs_mesh.h mesh/bs_vtu_read.h
    runfolder/bs_runfolder.h runfolder/bs_audit.h collision/bs_ls_sample.h
    study/bs_study.h)

get_property(BS_LIBRARIES GLOBAL PROPERTY BS_LIBRARIES)

# The objects of the folder libraries.
set(_bs_objects)
foreach(_lib IN LISTS BS_LIBRARIES)
  get_target_property(_type ${_lib} TYPE)
  if(_type STREQUAL "STATIC_LIBRARY")
    list(APPEND _bs_objects $<TARGET_OBJECTS:${_lib}>)
  endif()
endforeach()

# The public headers (absolute paths, names) and the names they declare:
# every bs_ identifier written in them (functions, data, types, macros) is
# exported by libbigstep.so; internal names (bs__x, and everything declared
# only in internal headers) are local.
set(_bs_headers)
set(_bs_header_names)
set(_bs_api_names)
foreach(_rel IN LISTS BS_PUBLIC_HEADERS)
  set(_h ${PROJECT_SOURCE_DIR}/${_rel})
  if(NOT EXISTS ${_h})
    message(FATAL_ERROR "bigstep: the public header ${_rel} does not exist (cmake/BigstepPackage.cmake)")
  endif()
  get_filename_component(_name ${_h} NAME)
  if(_name IN_LIST _bs_header_names)
    message(FATAL_ERROR "bigstep: two public headers named ${_name}; include/bigstep/ is flat")
  endif()
  list(APPEND _bs_headers ${_h})
  list(APPEND _bs_header_names ${_name})
  set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${_h})
  file(READ ${_h} _text)
  string(REGEX REPLACE "/\\*([^*]|\\*+[^*/])*\\*+/" "" _text "${_text}") # comments name other modules
  string(REGEX REPLACE "//[^\n]*" "" _text "${_text}")
  string(REGEX MATCHALL "bs_[a-z0-9][a-z0-9_]*" _ids "${_text}")
  list(APPEND _bs_api_names ${_ids})
endforeach()
list(REMOVE_DUPLICATES _bs_api_names)
list(SORT _bs_api_names)
set(_bs_map "/* libbigstep.so's exports (written by cmake/BigstepPackage.cmake from the\n * bs_ names of the public headers): the API, nothing internal. */\n{\n  global:\n")
foreach(_n IN LISTS _bs_api_names)
  string(APPEND _bs_map "    ${_n};\n")
endforeach()
string(APPEND _bs_map "  local: *;\n};\n")
file(CONFIGURE OUTPUT ${PROJECT_BINARY_DIR}/bigstep.map CONTENT "${_bs_map}")

# What the folder libraries link outside the project, in link order, read
# from their link interfaces: every BS_LIBRARIES target and INTERFACE target
# (bs_dep_*, MPI::MPI_C, CGAL::CGAL) is opened up to library paths, names
# and flags. OpenMP comes back as the word OPENMP (a flag in bigstep.pc, a
# find_dependency in bigstepConfig.cmake).
function(bs_external_link_items out)
  set(_pending ${ARGN})
  set(_seen)
  set(_items)
  while(_pending)
    list(POP_FRONT _pending _it)
    if(_it MATCHES "^\\$<LINK_ONLY:(.*)>$")
      set(_it "${CMAKE_MATCH_1}")
    endif()
    if(_it IN_LIST _seen)
      continue()
    endif()
    list(APPEND _seen "${_it}")
    if(_it MATCHES "^OpenMP::OpenMP_(C|CXX)$")
      list(APPEND _items OPENMP)
    elseif(TARGET ${_it})
      get_target_property(_real ${_it} ALIASED_TARGET)
      if(_real)
        list(PREPEND _pending ${_real})
        continue()
      endif()
      get_target_property(_type ${_it} TYPE)
      get_target_property(_imported ${_it} IMPORTED)
      if(_imported AND NOT _type STREQUAL "INTERFACE_LIBRARY")
        get_target_property(_loc ${_it} IMPORTED_LOCATION_RELEASE)
        if(NOT _loc)
          get_target_property(_loc ${_it} IMPORTED_LOCATION)
        endif()
        if(NOT _loc)
          message(FATAL_ERROR "bigstep: no library file for the imported target ${_it}")
        endif()
        list(APPEND _items ${_loc})
      elseif(NOT _it IN_LIST BS_LIBRARIES AND NOT _type STREQUAL "INTERFACE_LIBRARY")
        message(FATAL_ERROR "bigstep: the folder libraries link ${_it}, which is neither a dependency nor in BS_LIBRARIES")
      endif()
      get_target_property(_deps ${_it} INTERFACE_LINK_LIBRARIES)
      if(_deps)
        list(PREPEND _pending ${_deps})
      endif()
    elseif(_it MATCHES "\\$<")
      message(FATAL_ERROR "bigstep: cannot install the link item '${_it}' of the folder libraries")
    elseif(NOT _it STREQUAL "")
      list(APPEND _items "${_it}")
    endif()
  endwhile()
  # The shim's C++ needs its runtime in a C program's link; -lm last.
  list(APPEND _items stdc++ m)
  list(REVERSE _items)
  list(REMOVE_DUPLICATES _items) # keeps each item's last place in link order
  list(REVERSE _items)
  set(${out} ${_items} PARENT_SCOPE)
endfunction()
bs_external_link_items(_bs_link_items ${BS_LIBRARIES})
set(_bs_link_openmp)
set(_bs_pc_openmp)
if(OPENMP IN_LIST _bs_link_items)
  list(REMOVE_ITEM _bs_link_items OPENMP)
  set(_bs_link_openmp OpenMP::OpenMP_C)
  set(_bs_pc_openmp ${OpenMP_C_FLAGS})
endif()

# ---- the combined libraries ------------------------------------------------
# SONAME: while the major version is 0 every minor version may break the ABI,
# so the SONAME carries major.minor (libbigstep.so.0.1); from 1.0 on, major.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(_bs_soversion ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
else()
  set(_bs_soversion ${PROJECT_VERSION_MAJOR})
endif()

add_library(bigstep_static STATIC ${_bs_objects})
add_library(bigstep_shared SHARED ${_bs_objects})
set_target_properties(bigstep_static PROPERTIES OUTPUT_NAME bigstep EXPORT_NAME bigstep_static
                      ARCHIVE_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/lib)
set_target_properties(bigstep_shared PROPERTIES OUTPUT_NAME bigstep EXPORT_NAME bigstep
                      LIBRARY_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/lib
                      VERSION ${PROJECT_VERSION} SOVERSION ${_bs_soversion}
                      LINKER_LANGUAGE CXX INSTALL_RPATH_USE_LINK_PATH ON)
# The shared library resolves every symbol it uses at its own link, and
# exports only the names of the public headers (bigstep.map, above).
target_link_libraries(bigstep_shared PRIVATE ${_bs_link_items} ${_bs_link_openmp})
target_link_libraries(bigstep_shared INTERFACE m) # the public headers have inline math (bs_vec3.h)
target_link_options(bigstep_shared PRIVATE -Wl,--version-script=${PROJECT_BINARY_DIR}/bigstep.map)
set_property(TARGET bigstep_shared APPEND PROPERTY LINK_DEPENDS ${PROJECT_BINARY_DIR}/bigstep.map)
if(NOT BS_SANITIZE)
  target_link_options(bigstep_shared PRIVATE -Wl,--no-undefined)
endif()
# The static one hands its dependencies to whoever links it (OpenMP through
# bigstepConfig.cmake's find_dependency, outside the export).
target_link_libraries(bigstep_static INTERFACE ${_bs_link_items} $<BUILD_INTERFACE:${_bs_link_openmp}>)
foreach(_t bigstep_static bigstep_shared)
  target_include_directories(${_t} INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(BS_SANITIZE) # the objects call the sanitizer runtimes: so does every program linking them
    target_link_options(${_t} INTERFACE -fsanitize=address,undefined)
  endif()
endforeach()

# ---- the umbrella header ---------------------------------------------------
set(_bs_includes "")
foreach(_name IN LISTS _bs_header_names)
  string(APPEND _bs_includes "#include \"${_name}\"\n")
endforeach()
file(CONFIGURE OUTPUT ${PROJECT_BINARY_DIR}/include/bigstep/bigstep.h @ONLY CONTENT
"/* bigstep.h — every public header of bigstep @PROJECT_VERSION@ (written by
 * cmake/BigstepPackage.cmake). Each header opens with its conventions: units,
 * ownership, status codes.
 *
 *   #include <bigstep/bigstep.h>
 *   cc prog.c $(pkg-config --cflags --libs bigstep)
 */
#ifndef BIGSTEP_H
#define BIGSTEP_H

#define BIGSTEP_VERSION \"@PROJECT_VERSION@\"
#define BIGSTEP_VERSION_MAJOR @PROJECT_VERSION_MAJOR@
#define BIGSTEP_VERSION_MINOR @PROJECT_VERSION_MINOR@
#define BIGSTEP_VERSION_PATCH @PROJECT_VERSION_PATCH@

@_bs_includes@
#endif
")

# ---- pkg-config ------------------------------------------------------------
# Libs.private spells _bs_link_items as -L/-l (no -L for the compiler's own
# directories). No Requires.private: several dependencies (Gmsh, METIS,
# SuiteSparse, hypre) ship no .pc file, so all of them are listed alike.
set(_bs_pc_private "")
foreach(_it IN LISTS _bs_link_items)
  if(_it MATCHES "^-")
    string(APPEND _bs_pc_private " ${_it}")
  elseif(IS_ABSOLUTE "${_it}")
    get_filename_component(_dir "${_it}" DIRECTORY)
    get_filename_component(_name "${_it}" NAME_WE)
    string(REGEX REPLACE "^lib" "" _name "${_name}")
    if(NOT _dir IN_LIST CMAKE_C_IMPLICIT_LINK_DIRECTORIES AND NOT " ${_bs_pc_private} " MATCHES " -L${_dir} ")
      string(APPEND _bs_pc_private " -L${_dir}")
    endif()
    string(APPEND _bs_pc_private " -l${_name}")
  else()
    string(APPEND _bs_pc_private " -l${_it}")
  endif()
endforeach()
string(APPEND _bs_pc_private " ${_bs_pc_openmp}")
string(STRIP "${_bs_pc_private}" BS_PC_LIBS_PRIVATE)
set(BS_PC_LIBS "-L\${libdir} -lbigstep -lm") # -lm: the public headers have inline math (bs_vec3.h)
if(BS_SANITIZE)
  string(APPEND BS_PC_LIBS " -fsanitize=address,undefined")
endif()
foreach(_d LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${_d}}")
    set(BS_PC_${_d} "${CMAKE_INSTALL_${_d}}")
  else()
    set(BS_PC_${_d} "\${prefix}/${CMAKE_INSTALL_${_d}}")
  endif()
endforeach()
# The prefix is the one given to `cmake --install --prefix`, so the file is
# finished at install time.
set(BS_PC_PREFIX "@BS_PC_PREFIX@")
configure_file(${CMAKE_CURRENT_LIST_DIR}/bigstep.pc.in ${PROJECT_BINARY_DIR}/CMakeFiles/bigstep.pc.in @ONLY)

# ---- installation ----------------------------------------------------------
set(BS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/bigstep)
install(TARGETS bigstep_shared bigstep_static EXPORT bigstepTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(FILES ${_bs_headers} ${PROJECT_BINARY_DIR}/include/bigstep/bigstep.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/bigstep)
set_target_properties(bigstep PROPERTIES INSTALL_RPATH_USE_LINK_PATH ON)
install(TARGETS bigstep RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(_bs_pc_dest "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
else()
  set(_bs_pc_dest "\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/pkgconfig")
endif()
install(CODE "
  set(BS_PC_PREFIX \"\${CMAKE_INSTALL_PREFIX}\")
  configure_file(\"${PROJECT_BINARY_DIR}/CMakeFiles/bigstep.pc.in\" \"${PROJECT_BINARY_DIR}/CMakeFiles/pc/bigstep.pc\" @ONLY)
  file(INSTALL \"${PROJECT_BINARY_DIR}/CMakeFiles/pc/bigstep.pc\" DESTINATION \"${_bs_pc_dest}\")
")

install(EXPORT bigstepTargets NAMESPACE bigstep:: DESTINATION ${BS_CMAKE_DIR} FILE bigstepTargets.cmake)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/bigstepConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/CMakeFiles/bigstepConfig.cmake
                              INSTALL_DESTINATION ${BS_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/CMakeFiles/bigstepConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/CMakeFiles/bigstepConfig.cmake
              ${PROJECT_BINARY_DIR}/CMakeFiles/bigstepConfigVersion.cmake
        DESTINATION ${BS_CMAKE_DIR})
