# copy-assets.cmake - copies the page (web/*.html, web/*.js) and the shipped scene files
# (scenes/*.json, scenes/textures/) from SRC into the web build directory DST, and writes
# DST/scenes/index.json, the list of files the page loads into its file system.
file(GLOB pages ${SRC}/web/*.html ${SRC}/web/*.js)
file(COPY ${pages} DESTINATION ${DST})
file(GLOB scenes RELATIVE ${SRC}/scenes ${SRC}/scenes/*.json)
file(GLOB textures RELATIVE ${SRC}/scenes ${SRC}/scenes/textures/*)
list(SORT scenes)
list(SORT textures)
file(MAKE_DIRECTORY ${DST}/scenes/textures)
set(entries "")
foreach(f IN LISTS scenes textures)
  file(COPY_FILE ${SRC}/scenes/${f} ${DST}/scenes/${f} ONLY_IF_DIFFERENT)
  list(APPEND entries "\"${f}\"")
endforeach()
list(JOIN entries ",\n  " body)
file(WRITE ${DST}/scenes/index.json.tmp "[\n  ${body}\n]\n")
file(COPY_FILE ${DST}/scenes/index.json.tmp ${DST}/scenes/index.json)
file(REMOVE ${DST}/scenes/index.json.tmp)
