# cmake -DMANIFEST=<build>/sdk/manifest.cmake -P GenerateSdkHeaders.cmake (cmake/Sdk.cmake):
# writes OUTPUT_DIR/osgBTF/<layer>/<file>.h from the runtime's headers with their includes
# rewritten to <osgBTF/...>, the extension-less headers and <osgBTF/Version>. Files are rewritten
# only when their text changes (no needless recompiles) and files no longer in the manifest are
# removed.
cmake_minimum_required(VERSION 3.22)
include(${MANIFEST})
set(root ${OUTPUT_DIR}/osgBTF)
set(written)

function(write_if_changed path text)
  if(EXISTS ${path})
    file(READ ${path} old)
    if(old STREQUAL text)
      return()
    endif()
  endif()
  file(WRITE ${path} "${text}")
endfunction()

string(REPLACE ";" "|" layer_regex "${LAYERS}")
foreach(header IN LISTS HEADERS)
  file(READ ${SOURCE_DIR}/${header} text)
  string(REGEX REPLACE "#include \"((${layer_regex})/[^\"]+)\"" "#include <osgBTF/\\1>" text
         "${text}")
  string(REGEX MATCH "#[ \t]*include[ \t]*\"[^\"]+\"" leftover "${text}")
  if(leftover)
    message(FATAL_ERROR "${header}: ${leftover} is not part of the installed SDK "
                        "(a runtime header may include only ${LAYERS} headers)")
  endif()
  write_if_changed(${root}/${header} "${text}")
  list(APPEND written ${root}/${header})
endforeach()

foreach(entry IN LISTS UMBRELLAS)
  string(REGEX REPLACE "=.*" "" name "${entry}")
  string(REGEX REPLACE "^[^=]*=" "" headers "${entry}")
  # NAME=a.h+b.h: an umbrella of several headers (e.g. Material: the interface, the registry and
  # loading/saving, which are separate headers in the source tree).
  string(REPLACE "+" ";" headers "${headers}")
  list(JOIN headers ", " listed)
  set(text "// -*-c++-*- osgBTF ${VERSION}: <osgBTF/${name}> is ${listed}\n#pragma once\n")
  foreach(header IN LISTS headers)
    string(APPEND text "#include <osgBTF/${header}>\n")
  endforeach()
  write_if_changed(${root}/${name} "${text}")
  list(APPEND written ${root}/${name})
endforeach()

string(REPLACE "." ";" parts "${VERSION}")
list(GET parts 0 major)
list(GET parts 1 minor)
list(GET parts 2 patch)
write_if_changed(${root}/Version "// -*-c++-*- osgBTF ${VERSION}
#pragma once
#define OSGBTF_VERSION_MAJOR ${major}
#define OSGBTF_VERSION_MINOR ${minor}
#define OSGBTF_VERSION_PATCH ${patch}
#define OSGBTF_VERSION_STRING \"${VERSION}\"
")
list(APPEND written ${root}/Version)

file(GLOB_RECURSE existing ${root}/*)
foreach(file IN LISTS existing)
  if(NOT file IN_LIST written)
    file(REMOVE ${file})
  endif()
endforeach()
