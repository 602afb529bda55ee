# Turns a text file into a C++ string constant rtfuse::apps::${NAME}.
file(READ ${IN} content)
set(delim "rtfuse_embed")
file(WRITE ${OUT} "// Generated from ${IN}; do not edit.\n#include <string_view>\nnamespace rtfuse::apps {\nextern const std::string_view ${NAME};\nconst std::string_view ${NAME} = R\"${delim}(${content})${delim}\";\n}\n")
