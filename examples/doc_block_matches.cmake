# Fails unless the C code block of DOC that begins with FIRST_LINE equals the
# file SRC: the user guide shows examples/damped_chain.c, which CI compiles
# and runs, so the two must not drift apart.
# Usage: cmake -DDOC=user_guide.md -DSRC=damped_chain.c -P doc_block_matches.cmake
file(READ ${DOC} doc)
file(READ ${SRC} src)
string(FIND "${src}" "\n" eol)
string(SUBSTRING "${src}" 0 ${eol} first_line)
string(FIND "${doc}" "```c\n${first_line}" start)
if(start EQUAL -1)
  message(FATAL_ERROR "${DOC} has no code block starting with the first line of ${SRC}")
endif()
math(EXPR start "${start} + 5")
string(SUBSTRING "${doc}" ${start} -1 rest)
string(FIND "${rest}" "```" stop)
string(SUBSTRING "${rest}" 0 ${stop} block)
if(NOT block STREQUAL src)
  message(FATAL_ERROR "the code block in ${DOC} differs from ${SRC}")
endif()
