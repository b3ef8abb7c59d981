# Runs Doxygen on the configured Doxyfile with its output and warning log in a folder of its own,
# and fails when it reports any warning (the test Docs.NoWarnings).
#   cmake -DDOXYGEN=doxygen -DDOXYFILE=build/docs/Doxyfile -DOUTPUT=build/docs/check
#         -P docs/check_doxygen.cmake
foreach(variable DOXYGEN DOXYFILE OUTPUT)
  if(NOT DEFINED ${variable})
    message(FATAL_ERROR "check_doxygen.cmake: -D${variable}=... is missing")
  endif()
endforeach()

file(REMOVE_RECURSE ${OUTPUT})
file(MAKE_DIRECTORY ${OUTPUT})
file(READ ${DOXYFILE} configuration)
string(APPEND configuration "\n# check_doxygen.cmake\n"
                            "OUTPUT_DIRECTORY = ${OUTPUT}\n"
                            "WARN_LOGFILE = ${OUTPUT}/warnings.log\n")
file(WRITE ${OUTPUT}/Doxyfile "${configuration}")

execute_process(COMMAND ${DOXYGEN} ${OUTPUT}/Doxyfile
                RESULT_VARIABLE status OUTPUT_VARIABLE output ERROR_VARIABLE output)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "doxygen exited with ${status}:\n${output}")
endif()
if(NOT EXISTS ${OUTPUT}/warnings.log OR NOT EXISTS ${OUTPUT}/html/index.html)
  message(FATAL_ERROR "doxygen wrote no warning log or no html/index.html:\n${output}")
endif()
file(READ ${OUTPUT}/warnings.log warnings)
if(NOT warnings STREQUAL "")
  message(FATAL_ERROR "doxygen warnings (fix the comments they name):\n${warnings}")
endif()
message(STATUS "doxygen: no warnings")
