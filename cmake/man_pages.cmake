# Writes the man pages, one per subcommand and mbstorm(1) for the whole, with help2man from
# the built binary's own --help (so they say what the binary does), gzipped for installing.
# The subcommands are those `mbstorm --help` lists: a new one gets its page without an edit.
#   cmake -DMBSTORM=... -DHELP2MAN=... -DVERSION=... -DOUT_DIR=... -P man_pages.cmake
file(REMOVE_RECURSE "${OUT_DIR}")
file(MAKE_DIRECTORY "${OUT_DIR}/wrappers")

execute_process(COMMAND "${MBSTORM}" --help OUTPUT_VARIABLE help COMMAND_ERROR_IS_FATAL ANY)
string(REGEX REPLACE ".*\nSubcommands:\n" "" listing "${help}")
# A ';' would split CMake's list of lines: stand it in for now.
string(REPLACE ";" "<semicolon>" listing "${listing}")
string(REGEX MATCHALL "  [a-z][a-z-]* +[^\n]*" lines "${listing}")
set(subcommands "")
set(see_also "")
foreach(line IN LISTS lines)
  string(REGEX REPLACE "^  ([a-z-]+) +(.*)$" "\\1" name "${line}")
  string(REGEX REPLACE "^  ([a-z-]+) +(.*)$" "\\2" summary "${line}")
  string(REPLACE "<semicolon>" ";" summary "${summary}")
  # Man page names start in lower case ("run a load test"), like the rest of section 1.
  string(SUBSTRING "${summary}" 0 1 first)
  string(SUBSTRING "${summary}" 1 -1 rest)
  string(TOLOWER "${first}" first)
  list(APPEND subcommands "${name}")
  set(summary_${name} "${first}${rest}")
  string(APPEND see_also ".BR mbstorm-${name} (1),\n")
endforeach()
string(REGEX REPLACE ",\n$" "\n" see_also "${see_also}")
if(NOT subcommands)
  message(FATAL_ERROR "no subcommands in `${MBSTORM} --help`:\n${help}")
endif()

# The "Heading:" blocks a subcommand's --help ends with (Examples, Exit status, Files) as man
# sections of their own, lines kept as written (help2man would run them together).
function(footer_sections help out_var)
  set(sections "")
  foreach(heading Examples "Exit status" Files)
    if(help MATCHES "\n${heading}:\n(([^\n]+\n)+)")
      string(TOUPPER "${heading}" upper)
      string(REPLACE "\\" "\\e" block "${CMAKE_MATCH_1}")
      string(REGEX REPLACE "(^|\n)  " "\\1" block "${block}")
      string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" block "${block}")
      string(APPEND sections "[${upper}]\n.nf\n${block}.fi\n")
    endif()
  endforeach()
  set(${out_var} "${sections}" PARENT_SCOPE)
endfunction()

function(write_page command name summary see_also_text)
  set(footer "")
  if(name MATCHES "^mbstorm-(.+)$")
    execute_process(COMMAND "${MBSTORM}" ${CMAKE_MATCH_1} --help OUTPUT_VARIABLE sub_help)
    footer_sections("${sub_help}" footer)
  endif()
  file(WRITE "${OUT_DIR}/wrappers/${name}.h2m" "${footer}[SEE ALSO]\n${see_also_text}")
  execute_process(
    COMMAND "${HELP2MAN}" --no-info --no-discard-stderr "--version-string=${VERSION}"
            "--name=${summary}" "--include=${OUT_DIR}/wrappers/${name}.h2m"
            "--output=${OUT_DIR}/${name}.1" "${command}"
    COMMAND_ERROR_IS_FATAL ANY)
  # No hyphenation: an option broken as --tar-get cannot be copied or searched for.
  file(READ "${OUT_DIR}/${name}.1" page)
  string(REPLACE "\n.SH NAME\n" "\n.nh\n.SH NAME\n" page "${page}")
  file(WRITE "${OUT_DIR}/${name}.1" "${page}")
  execute_process(COMMAND gzip -9nf "${OUT_DIR}/${name}.1" COMMAND_ERROR_IS_FATAL ANY)
endfunction()

string(REPLACE ";" ", " listed "${subcommands}")
write_page("${MBSTORM}" mbstorm "Modbus TCP load tester, reference slave and fuzzer" "${see_also}")
foreach(name IN LISTS subcommands)
  # help2man names a page after the program it runs: a wrapper called mbstorm-<name>.
  set(wrapper "${OUT_DIR}/wrappers/mbstorm-${name}")
  # The footer's blocks go in as sections of their own (footer_sections): help2man sees the
  # help without them.
  file(WRITE "${wrapper}"
       "#!/bin/sh\n'${MBSTORM}' ${name} \"$@\" | sed '/^Examples:$/,$d'\n")
  file(CHMOD "${wrapper}" PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE)
  write_page("${wrapper}" "mbstorm-${name}" "${summary_${name}}" ".BR mbstorm (1)\n")
endforeach()
file(REMOVE_RECURSE "${OUT_DIR}/wrappers")
