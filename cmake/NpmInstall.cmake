# cmake -DWEB=<web dir> -DNPM=<npm> -P NpmInstall.cmake
# What building the web page needs from npm: esbuild (package.json "dependencies"). Installs
# with `npm ci --omit=dev` only when esbuild is missing or package-lock.json changed since the
# last install; a full install (the test tools, scripts/setup.sh) stays a full one.
if(EXISTS "${WEB}/node_modules/.bin/esbuild" AND
   NOT "${WEB}/package-lock.json" IS_NEWER_THAN "${WEB}/node_modules/.package-lock.json")
  return()
endif()
set(omit --omit=dev)
if(EXISTS "${WEB}/node_modules/playwright-core")
  set(omit "")
endif()
message(STATUS "npm ci ${omit} in ${WEB} (esbuild for the web page)")
execute_process(COMMAND "${NPM}" ci ${omit} --no-audit --no-fund --loglevel=error
                WORKING_DIRECTORY "${WEB}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "npm ci in ${WEB} failed (${rc}): the build needs the npm registry once")
endif()
