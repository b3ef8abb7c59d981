# ISA.NoSharedCodeBetweenInstructionSets (tests/CMakeLists.txt): no code built for one
# instruction set can stand in for another's at link time. An inline or template function that a
# per-ISA object emits out of line is a weak symbol; where another object (the library's own,
# built for the baseline, or another ISA's) defines the same symbol, the linker keeps one of the
# copies for every caller, and a baseline caller could run AVX-512 code on a CPU without it.
# Fails, naming them, where an object built with flags beyond the baseline defines a weak symbol
# that an object outside its own ISA defines too.
#
# cmake -DNM=nm -DLIBRARY=a.o|b.o|… -DISAS=scalar|sse2|avx2|… -DFLAGGED=avx2|… -DISA_avx2=x.o|…
#       -P this
string(REPLACE "|" ";" library "${LIBRARY}")
string(REPLACE "|" ";" isas "${ISAS}")
string(REPLACE "|" ";" flagged "${FLAGGED}")

# The code symbols (T, W, t excluded: local) each object list defines: "name" lines.
function(defined_code objects out)
  set(symbols "")
  foreach(object ${objects})
    execute_process(COMMAND ${NM} --defined-only ${object} OUTPUT_VARIABLE listing
                    RESULT_VARIABLE failed)
    if(failed)
      message(FATAL_ERROR "${NM} failed on ${object}")
    endif()
    string(REGEX MATCHALL "[0-9a-f]+ [TW] [^\n]+" lines "${listing}")
    foreach(line ${lines})
      string(REGEX REPLACE "^[0-9a-f]+ ([TW]) (.+)$" "\\1 \\2" entry "${line}")
      list(APPEND symbols "${entry}")
    endforeach()
  endforeach()
  set(${out} "${symbols}" PARENT_SCOPE)
endfunction()

defined_code("${library}" library_symbols)
string(REGEX REPLACE "(^|;)[TW] " "\\1" library_names "${library_symbols}")
# Each ISA's symbols, read once.
foreach(isa ${isas})
  string(REPLACE "|" ";" objects "${ISA_${isa}}")
  defined_code("${objects}" symbols_${isa})
  string(REGEX REPLACE "(^|;)[TW] " "\\1" names_${isa} "${symbols_${isa}}")
endforeach()
set(shared "")
set(checked 0)
foreach(isa ${flagged})
  set(others ${library_names})
  foreach(other ${isas})
    if(NOT other STREQUAL isa)
      list(APPEND others ${names_${other}})
    endif()
  endforeach()
  foreach(entry ${symbols_${isa}})
    # clang's __clang_call_terminate (a noexcept function's landing pad: __cxa_begin_catch, then
    # std::terminate) is the same few instructions whatever the flags.
    if(entry MATCHES "^W (.+)$" AND NOT entry STREQUAL "W __clang_call_terminate")
      set(name "${CMAKE_MATCH_1}")
      math(EXPR checked "${checked} + 1")
      list(FIND others "${name}" found)
      if(NOT found EQUAL -1)
        list(APPEND shared "${isa}: ${name}")
      endif()
    endif()
  endforeach()
endforeach()
if(shared)
  list(JOIN shared "\n  " text)
  message(FATAL_ERROR "code of one ISA that another object defines too:\n  ${text}")
endif()
message(STATUS "${checked} weak symbols of the ISAs ${flagged}, none defined elsewhere")
