# Writes a C++ source holding a file's bytes (cmake -DINPUT=... -DOUTPUT=... -DSYMBOL=... -P):
# the HTML report's inlined JavaScript library, read from its Debian package at build time.
file(READ "${INPUT}" hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," bytes "${hex}")
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${INPUT} by validator/report/embed_file.cmake.\n"
  "#include <cstddef>\n"
  "namespace ncservo::report {\n"
  "extern const char ${SYMBOL}[];\n"
  "extern const std::size_t ${SYMBOL}Size;\n"
  "const char ${SYMBOL}[] = {${bytes}};\n"
  "const std::size_t ${SYMBOL}Size = ${size};\n"
  "}  // namespace ncservo::report\n")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
