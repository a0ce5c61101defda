# pytest files and folders as CTest tests (issue #80 item 7), so that the ecosystem's runners see
# every test: `catkin_make run_tests`, and `ctest -j N` in the build folder (scripts/test.sh with
# ASG_TEST_RUNNER=ctest). Each is run by catkin's run_tests.py, which writes a failing JUnit file
# when pytest wrote none; results go to build/test_results/PACKAGE/pytest-NAME.xml. No two of the
# suite's tests share a port (each that starts a master names its own), so none needs a lock.
#   include(<repository>/scripts/ci/pytest.cmake)
#   asg_add_pytest(NAME FILE_OR_FOLDER [pytest options ...])
#   asg_add_pytest_files(FOLDER)      # one test a test_*.py file of FOLDER
get_filename_component(ASG_REPO "${CMAKE_CURRENT_LIST_DIR}/../.." REALPATH)

function(asg_add_pytest name)
  set(xml "${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME}/pytest-${name}.xml")
  # run_tests.py takes each command as one shell string (its own options would take pytest's)
  string(REPLACE ";" " " args "${ARGN}")
  catkin_run_tests_target("pytest" ${name} "pytest-${name}.xml"
    COMMAND "/usr/bin/python3 -m pytest -q -p no:cacheprovider --junitxml=${xml} ${args}"
    WORKING_DIRECTORY ${ASG_REPO})
  set_tests_properties(_ctest_${PROJECT_NAME}_pytest_${name} PROPERTIES LABELS pytest)
endfunction()

function(asg_add_pytest_files folder)
  file(GLOB files CONFIGURE_DEPENDS "${folder}/test_*.py")
  foreach(f ${files})
    get_filename_component(stem ${f} NAME_WE)
    asg_add_pytest(${stem} ${f})
  endforeach()
endfunction()
