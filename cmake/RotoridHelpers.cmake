# Compile options for our own code only (dependencies are never built with -Werror or sanitizers).
function(rotorid_target_options target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wnon-virtual-dtor)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wshadow=local)
  endif()
  if(ROTORID_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(ROTORID_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined)
    # The numeric modules and the tests skip three of UBSan's checks, which cost about a third of
    # their compile time under the sanitizers (tls.cc 79 -> 54 s of CPU; the CI's sanitizer build
    # dominates its time): a null dereference still faults under ASan with a stack, Eigen's own
    # assertions (on in this Debug build) check the alignment of its fixed-size objects, and the
    # effect descriptors are reached through their base class only. The readers of logs, the CLI
    # and core keep every check: misaligned reads of packed binary logs are where `alignment` finds
    # real bugs.
    if(NOT target MATCHES "^rotorid_(io|core|cli)$")
      target_compile_options(${target} PRIVATE -fno-sanitize=null,alignment,vptr)
    endif()
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
    # Eigen stops trusting glibc's 16-byte-aligned malloc under ASan and switches to its own
    # aligned allocator, which frees by reading a header before the block: an Eigen object that
    # Ceres (built without ASan) allocated and our code frees then reads out of bounds. glibc's
    # malloc is 16-byte aligned on x86-64, so keep Eigen's allocation as the libraries have it.
    target_compile_definitions(${target} PUBLIC EIGEN_MALLOC_ALREADY_ALIGNED=1)
    # GCC's flow analysis under the sanitizers reports libstdc++'s own <regex> and <functional>
    # internals as maybe uninitialised; the sanitizers check the real thing at run time.
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
      target_compile_options(${target} PRIVATE -Wno-maybe-uninitialized)
    endif()
  endif()
endfunction()

# rotorid_add_module(name DEPS ...): a static component built from src/<name>/*.cc.
function(rotorid_add_module name)
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/${name}/*.cc)
  add_library(rotorid_${name} STATIC ${sources} ${PROJECT_SOURCE_DIR}/src/module_anchor.cc)
  target_include_directories(rotorid_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>)
  target_include_directories(rotorid_${name} PRIVATE ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(rotorid_${name} PUBLIC ${ARG_DEPS})
  target_compile_features(rotorid_${name} PUBLIC cxx_std_17)
  rotorid_target_options(rotorid_${name})
  set(ROTORID_MODULES ${ROTORID_MODULES} rotorid_${name} PARENT_SCOPE)
endfunction()

# rotorid_add_test(file.cc): one GoogleTest executable per file, each test registered with CTest.
# rotorid_add_test(source [WHOLE]): one CTest test per GoogleTest case, or with WHOLE one for the
# whole executable, for suites whose SetUpTestSuite is the expensive part (simulate, identify,
# refine, diagnose): per-case processes would repeat it for every case.
function(rotorid_add_test source)
  cmake_parse_arguments(ARG "WHOLE" "" "" ${ARGN})
  get_filename_component(name ${source} NAME_WE)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE rotorid::rotorid rotorid_test_support GTest::gtest GTest::gmock GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/src)
  rotorid_target_options(${name})
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE OFF)
  target_precompile_headers(${name} REUSE_FROM rotorid_test_support)
  add_dependencies(${name} rotorid_cli)  # end-to-end tests run the CLI binary
  if(ARG_WHOLE)
    add_test(NAME ${name} COMMAND ${name})
    set_tests_properties(${name} PROPERTIES ENVIRONMENT "ROTORID_SOURCE_DIR=${PROJECT_SOURCE_DIR};ROTORID_BINARY=$<TARGET_FILE:rotorid_cli>")
    return()
  endif()
  # One variable per property: gtest_discover_tests splits a "A=1;B=2" ENVIRONMENT value into two
  # properties, which left ROTORID_BINARY unset.
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                       PROPERTIES ENVIRONMENT "ROTORID_SOURCE_DIR=${PROJECT_SOURCE_DIR}"
                                  ENVIRONMENT_MODIFICATION "ROTORID_BINARY=set:$<TARGET_FILE:rotorid_cli>")
endfunction()
