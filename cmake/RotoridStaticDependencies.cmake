# Links the libraries behind Ceres, glog and yaml-cpp from their static archives where Debian's
# -dev packages ship them. The rotorid process otherwise maps 26 shared libraries (Ceres pulls in
# SuiteSparse, ATLAS and the Fortran runtime), which cost about 7 ms of every command's start on
# the project's machine: a fifth of an `identify` of a 90 s log (docs/benchmarks.md). A library
# without an archive (METIS) stays shared; nothing changes where no archive is installed.

# The archive beside a shared library path (libx.so or libx.so.1.2.3 -> libx.a), or "".
function(_rotorid_archive_of path out)
  set(archive "")
  if(path MATCHES "^(.*)\\.so(\\.[0-9.]+)?$")
    if(EXISTS "${CMAKE_MATCH_1}.a")  # a separate if: ${} is expanded before MATCHES sets it
      set(archive "${CMAKE_MATCH_1}.a")
    endif()
  endif()
  set(${out} "${archive}" PARENT_SCOPE)
endfunction()

# A static archive of the compiler's runtime (libgfortran.a, libquadmath.a), or "".
function(_rotorid_compiler_archive name out)
  execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=${name} OUTPUT_VARIABLE path
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(IS_ABSOLUTE "${path}" AND EXISTS "${path}")
    set(${out} "${path}" PARENT_SCOPE)
  else()
    set(${out} "" PARENT_SCOPE)
  endif()
endfunction()

# Rewrites an imported target, and the imported targets and library paths it links, to archives.
# `extra` collects what the archives need that the shared libraries brought themselves.
function(_rotorid_make_static item)
  if(NOT TARGET "${item}")
    return()
  endif()
  get_target_property(imported "${item}" IMPORTED)
  get_property(visited GLOBAL PROPERTY ROTORID_STATIC_VISITED)
  if(NOT imported OR "${item}" IN_LIST visited)
    return()
  endif()
  set_property(GLOBAL APPEND PROPERTY ROTORID_STATIC_VISITED "${item}")
  foreach(property IMPORTED_LOCATION IMPORTED_LOCATION_RELEASE IMPORTED_LOCATION_NONE IMPORTED_LOCATION_NOCONFIG)
    get_target_property(location "${item}" ${property})
    if(location)
      _rotorid_archive_of("${location}" archive)
      if(archive)
        set_target_properties("${item}" PROPERTIES ${property} "${archive}")
      endif()
    endif()
  endforeach()
  get_target_property(links "${item}" INTERFACE_LINK_LIBRARIES)
  if(NOT links)
    return()
  endif()
  set(rewritten "")
  foreach(link IN LISTS links)
    set(inner "${link}")
    if(link MATCHES "^\\$<LINK_ONLY:(.*)>$")
      set(inner "${CMAKE_MATCH_1}")
    endif()
    if(TARGET "${inner}")
      _rotorid_make_static("${inner}")
    elseif(IS_ABSOLUTE "${inner}")
      _rotorid_archive_of("${inner}" archive)
      if(archive)
        string(REPLACE "${inner}" "${archive}" link "${link}")
      endif()
    endif()
    list(APPEND rewritten "${link}")
  endforeach()
  set_target_properties("${item}" PROPERTIES INTERFACE_LINK_LIBRARIES "${rewritten}")
endfunction()

# rotorid_prefer_static_archives(TARGETS ...): call after find_package of those targets.
function(rotorid_prefer_static_archives)
  # The Fortran LAPACK and BLAS archives need the Fortran runtime, the SuiteSparse ones OpenMP's
  # and METIS (shared: Debian ships no archive of it), glog's its unwinder: the shared libraries
  # linked those themselves.
  _rotorid_compiler_archive(libgfortran.a gfortran)
  _rotorid_compiler_archive(libquadmath.a quadmath)
  find_package(OpenMP COMPONENTS CXX QUIET)
  find_library(ROTORID_UNWIND_LIBRARY unwind)
  find_library(ROTORID_METIS_LIBRARY NAMES metis libmetis.so.5)
  if(NOT gfortran OR NOT quadmath OR NOT OpenMP_gomp_LIBRARY OR NOT ROTORID_UNWIND_LIBRARY OR NOT ROTORID_METIS_LIBRARY)
    message(STATUS "rotorid: shared dependencies (no libgfortran.a, libquadmath.a, libgomp, libunwind or libmetis)")
    return()
  endif()
  foreach(target IN LISTS ARGN)
    _rotorid_make_static("${target}")
  endforeach()
  set_property(TARGET Ceres::ceres APPEND PROPERTY INTERFACE_LINK_LIBRARIES
                                                   "${ROTORID_METIS_LIBRARY}" "${gfortran}" "${quadmath}"
                                                   "${OpenMP_gomp_LIBRARY}")
  set_property(TARGET glog::glog APPEND PROPERTY INTERFACE_LINK_LIBRARIES "${ROTORID_UNWIND_LIBRARY}")
  message(STATUS "rotorid: glog, gflags, yaml-cpp, SuiteSparse and LAPACK from static archives")
endfunction()
