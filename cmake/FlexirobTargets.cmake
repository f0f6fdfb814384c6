# Shared compile settings for every FlexIRob target.
function(flexirob_target_settings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wold-style-cast -Wcast-align -Woverloaded-virtual
                                           -Wnull-dereference -Wdouble-promotion -Wformat=2)
  if(FLEXIROB_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  # Sanitizer builds (scripts/test-sanitizers.sh): every report aborts the test that caused it
  # (-fno-sanitize-recover), so a UBSan finding fails CTest instead of scrolling past.
  if(FLEXIROB_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=${FLEXIROB_SANITIZE} -fno-omit-frame-pointer
                                             -fno-sanitize-recover=all)
    target_link_options(${target} PRIVATE -fsanitize=${FLEXIROB_SANITIZE})
  endif()
  # Fuzzer builds (clang only, scripts/fuzz.sh): the libraries get libFuzzer's coverage
  # instrumentation plus ASan and UBSan; the fuzz targets add the libFuzzer main (fuzz/).
  if(FLEXIROB_BUILD_FUZZERS)
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link,address,undefined
                                             -fno-sanitize-recover=all -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# A library of one layer: sources, public include root is the repository root so that
# includes read as "robot/kinematics.hpp".
function(flexirob_add_library target)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  add_library(${target} STATIC ${ARG_SOURCES})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  flexirob_target_settings(${target})
endfunction()

# One GoogleTest executable per module suite, registered with CTest.
function(flexirob_add_test target)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;LIBS" ${ARGN})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main Threads::Threads)
  target_compile_definitions(${target} PRIVATE
    FLEXIROB_TEST_RESOURCE_DIR="${FLEXIROB_SOURCE_RESOURCE_DIR}"
    FLEXIROB_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data")
  flexirob_target_settings(${target})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  # Labelled with the suite so that a sanitizer run can pick whole suites (ctest -L app_tests);
  # a test added to a suite later is picked up without being named anywhere.
  gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS ${target}
                       ENVIRONMENT "FLEXIROB_RESOURCES=${FLEXIROB_SOURCE_RESOURCE_DIR}")
endfunction()
