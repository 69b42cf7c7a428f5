# cmake -DSOURCE_DIR=<repo> -DDEPS_FILE=<build>/objmap_module_deps.cmake -P check_module_includes.cmake
#
# Every `#include "objmap/<other>/..."` in lib/objmap/<module>/ must name a module that <module>
# declares in its objmap_module(... DEPS ... PRIVATE_DEPS ...) call: declared directly, not merely
# reached through another module. DEPS_FILE is written by objmap_module at configure time (one
# OBJMAP_DEPS_<module> list per module, and OBJMAP_MODULE_NAMES). Fails with one line per include
# that is not declared. Run as the CTest test deps/ModuleIncludesAreDeclared.
cmake_minimum_required(VERSION 3.18)
if(NOT SOURCE_DIR OR NOT DEPS_FILE)
  message(FATAL_ERROR "usage: cmake -DSOURCE_DIR=.. -DDEPS_FILE=.. -P check_module_includes.cmake")
endif()
include(${DEPS_FILE})

set(violations 0)
foreach(module ${OBJMAP_MODULE_NAMES})
  file(GLOB_RECURSE files ${SOURCE_DIR}/lib/objmap/${module}/*.h ${SOURCE_DIR}/lib/objmap/${module}/*.cpp)
  list(SORT files)
  foreach(file ${files})
    file(STRINGS ${file} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<]objmap/[a-z0-9_]+/")
    foreach(line ${lines})
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[\"<]objmap/([a-z0-9_]+)/.*" "\\1" used "${line}")
      if(NOT used STREQUAL module AND NOT "objmap_${used}" IN_LIST OBJMAP_DEPS_${module})
        file(RELATIVE_PATH rel ${SOURCE_DIR} ${file})
        message("${rel}: includes objmap/${used}/ but objmap_${module} does not declare objmap_${used} "
                "(DEPS or PRIVATE_DEPS in its objmap_module call)")
        math(EXPR violations "${violations} + 1")
      endif()
    endforeach()
  endforeach()
endforeach()

list(LENGTH OBJMAP_MODULE_NAMES modules)
if(violations GREATER 0)
  message(FATAL_ERROR "${violations} include(s) of undeclared modules")
endif()
message("${modules} modules: every objmap/<module>/ include is declared")
