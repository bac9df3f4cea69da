# Included by CTest (TEST_INCLUDE_FILES) where WT_TEST_SUITES is on: one CTest
# test per gtest suite of one binary instead of one per case, so a suite's
# cases share a process (the device, the cached programs, the sanitizer's
# start-up). Set before including: wt_binary, wt_label, wt_env,
# wt_release_only (cases that keep a test of their own, labelled
# release-only, and leave their suite's run; an entry `Suite.*` makes the
# whole suite one test labelled release-only).
execute_process(COMMAND "${wt_binary}" --gtest_list_tests
  OUTPUT_VARIABLE wt_listing RESULT_VARIABLE wt_rc ERROR_QUIET)
get_filename_component(wt_name "${wt_binary}" NAME)
if(NOT wt_rc EQUAL 0)
  # a test that fails, saying why, rather than tests that vanish
  add_test("${wt_name}.list" "${wt_binary}" --gtest_list_tests)
  return()
endif()
string(REPLACE ";" "," wt_listing "${wt_listing}")
string(REPLACE "[" "(" wt_listing "${wt_listing}")
string(REPLACE "]" ")" wt_listing "${wt_listing}")
string(REPLACE "\n" ";" wt_lines "${wt_listing}")
set(wt_suites "")
set(wt_release_suites "")
set(wt_suite "")
foreach(wt_line IN LISTS wt_lines)
  if(wt_line MATCHES "^([^ #][^ ]*)\\.")
    set(wt_suite "${CMAKE_MATCH_1}")
  elseif(wt_line MATCHES "^  ([^ ]+)" AND wt_suite)
    set(wt_case "${wt_suite}.${CMAKE_MATCH_1}")
    set(wt_labels "${wt_label}")
    if(wt_suite MATCHES "Assets$")
      set(wt_labels "assets;${wt_labels}")
    endif()
    # (list(FIND), not if(IN_LIST): CTest reads this file under old policies)
    list(FIND wt_release_only "${wt_case}" wt_at)
    list(FIND wt_release_only "${wt_suite}.*" wt_suite_at)
    list(FIND wt_suites "${wt_suite}" wt_seen)
    if(wt_suite_at GREATER -1)
      list(FIND wt_release_suites "${wt_suite}" wt_seen)
      if(wt_seen EQUAL -1)
        list(APPEND wt_release_suites "${wt_suite}")
        add_test("${wt_suite}.*" "${wt_binary}" "--gtest_filter=${wt_suite}.*")
        set_tests_properties("${wt_suite}.*" PROPERTIES LABELS "release-only;${wt_labels}"
          ENVIRONMENT "${wt_env}" SKIP_REGULAR_EXPRESSION "\\[  SKIPPED \\]")
      endif()
    elseif(wt_at GREATER -1)
      add_test("${wt_case}" "${wt_binary}" "--gtest_filter=${wt_case}")
      set_tests_properties("${wt_case}" PROPERTIES LABELS "release-only;${wt_labels}"
        ENVIRONMENT "${wt_env}" SKIP_REGULAR_EXPRESSION "\\[  SKIPPED \\]")
    elseif(wt_seen EQUAL -1)
      list(APPEND wt_suites "${wt_suite}")
      set(wt_labels_${wt_suite} "${wt_labels}")
    endif()
  endif()
endforeach()
string(JOIN ":" wt_exclude ${wt_release_only})
foreach(wt_suite IN LISTS wt_suites)
  add_test("${wt_suite}.*" "${wt_binary}" "--gtest_filter=${wt_suite}.*-${wt_exclude}")
  set_tests_properties("${wt_suite}.*" PROPERTIES LABELS "${wt_labels_${wt_suite}}" ENVIRONMENT "${wt_env}")
  # a suite reading ../shared/assets skips as a whole where it is absent
  if(wt_suite MATCHES "Assets$")
    set_tests_properties("${wt_suite}.*" PROPERTIES SKIP_REGULAR_EXPRESSION "\\[  SKIPPED \\]")
  endif()
endforeach()
