# Writes OUT, a C++ source defining `extern const char NAME[]`, the bytes of IN and a final 0:
# how the viewer's checked-in bundle and page template reach the binary (cli/viewer_page.cpp).
#   cmake -DIN=file -DOUT=file.cpp -DNAME=kName -P embed_text.cmake
file(READ "${IN}" hex HEX)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," bytes "${hex}")
string(REGEX REPLACE "(([^,]*,){24})" "\\1\n  " bytes "${bytes}")
file(WRITE "${OUT}.tmp" "// Generated from ${IN} by cmake/embed_text.cmake: do not edit.\nnamespace prtsub {\nextern const char ${NAME}[];\nconst char ${NAME}[] = {\n  ${bytes}'\\0'};\n}  // namespace prtsub\n")
file(RENAME "${OUT}.tmp" "${OUT}")
