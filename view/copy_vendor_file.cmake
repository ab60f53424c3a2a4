# Copies one file of web/node_modules into the page's assets, with the fix when it is missing.
if(NOT EXISTS ${FILE})
  message(FATAL_ERROR "${FILE} is missing: the page's libraries come from npm; run `npm ci` in "
                      "web/ (.ci/setup does) and build again")
endif()
configure_file(${FILE} ${OUT} COPYONLY)
