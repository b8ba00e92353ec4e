# Writes a man page (section 1) from a program's --help, and from the --help
# of each of its subcommands when it has some (CLI11's "Subcommands:" list).
#   cmake -DPROGRAM=path -DNAME=name -DVERSION=x.y.z -DOUTPUT=file.1 -P help_to_man.cmake
# Run at build time, so the pages always say what the installed programs say.
foreach(var PROGRAM NAME VERSION OUTPUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "help_to_man.cmake: -D${var}=... is required")
  endif()
endforeach()

function(moco_help out)
  execute_process(COMMAND ${PROGRAM} ${ARGN} --help OUTPUT_VARIABLE text RESULT_VARIABLE rc
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${NAME} ${ARGN} --help exited ${rc}: ${err}")
  endif()
  # The build tree's path to the program is not what a user types.
  string(REPLACE "${PROGRAM}" "${NAME}" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# roff: a backslash is \e; a line starting with . or ' would be a request.
function(moco_roff out text)
  string(REPLACE "\\" "\\e" text "${text}")
  string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

moco_help(help)
string(REGEX MATCH "^[^\n]*" first_line "${help}")
string(REGEX REPLACE "^${NAME}: *" "" summary "${first_line}")
moco_roff(summary "${summary}")
moco_roff(body "${help}")
set(page ".TH ${NAME} 1 \"\" \"mocosim ${VERSION}\" \"User Commands\"\n")
string(APPEND page ".SH NAME\n${NAME} \\- ${summary}\n.SH DESCRIPTION\n.nf\n${body}\n.fi\n")

# Subcommands: the names listed under "Subcommands:" up to the next blank line.
string(FIND "${help}" "\nSubcommands:\n" at)
if(at GREATER -1)
  string(SUBSTRING "${help}" ${at} -1 rest)
  string(REGEX REPLACE "^\nSubcommands:\n" "" rest "${rest}")
  string(REGEX REPLACE "\n\n.*" "" rest "${rest}")
  string(REPLACE "\n" ";" lines "${rest}")
  string(APPEND page ".SH SUBCOMMANDS\n")
  foreach(line IN LISTS lines)
    if(line MATCHES "^  ([a-z0-9][a-z0-9_-]*) ")
      set(sub "${CMAKE_MATCH_1}")
      moco_help(sub_help ${sub})
      moco_roff(sub_body "${sub_help}")
      string(APPEND page ".SS \"${NAME} ${sub}\"\n.nf\n${sub_body}\n.fi\n")
    endif()
  endforeach()
endif()
string(APPEND page ".SH SEE ALSO\nmocosim(1), mococheck(1), dmc-host(1); "
                   "the documentation in /usr/share/doc/mocosim and the project's docs/ folder\n")
file(WRITE "${OUTPUT}.tmp" "${page}")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
