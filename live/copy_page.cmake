# Run on every build of sinew-live (cmake -P; file(COPY) skips unchanged files): puts the page and the parts of three.js it loads beside
# the tool, in <build>/live/web and <build>/live/three, so a build used from elsewhere or copied
# away serves its page without the source tree's .cache/ (issue 34). three.js comes from where
# scripts/install-deps puts it; without it the tool falls back to the source tree and says how to
# get it. Arguments: -DWEB=<live/web> -DTHREE=<.cache/three/node_modules/three> -DDEST=<dir>.
file(COPY "${WEB}/" DESTINATION "${DEST}/web")
if(EXISTS "${THREE}/build/three.module.js")
  # The module build (three.module.js imports three.core.js) and the controls the page imports.
  file(COPY "${THREE}/build/three.module.js" "${THREE}/build/three.core.js"
       DESTINATION "${DEST}/three/build")
  file(COPY "${THREE}/package.json" "${THREE}/LICENSE" DESTINATION "${DEST}/three")
  file(COPY "${THREE}/examples/jsm/controls" DESTINATION "${DEST}/three/examples/jsm")
else()
  message(STATUS "sinew-live: no three.js at ${THREE} (scripts/install-deps installs it); "
                 "the page cannot be served until it is there")
endif()
