# The program cache through the command line (`wavetrace render -v`): the
# first run on an empty cache compiles and stores, the second loads; two
# processes started together on an empty cache both succeed and leave one
# valid entry per program (the render program and the frame program); other
# build options (the minimal integrator) miss, and share the frame program;
# with the default folder on PoCL's CPU device a background process stores.
# Inputs: EXE (wavetrace), SCRATCH (a folder this test may empty).
set(cache "${SCRATCH}/kernels")
file(REMOVE_RECURSE "${SCRATCH}")
file(MAKE_DIRECTORY "${SCRATCH}")
set(tiny --width 8 --height 8 --spp 1 -v)
set(cached ${tiny} --kernel-cache "${cache}")

function(render name pattern)
  execute_process(COMMAND ${EXE} render -o "${SCRATCH}/${name}.png" ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
  message("${name}: exit status ${rc}\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: expected success, got exit status ${rc}")
  endif()
  if(NOT "${out}${err}" MATCHES "${pattern}")
    message(FATAL_ERROR "${name}: output does not match '${pattern}'")
  endif()
  set(out "${out}" PARENT_SCOPE)
  set(err "${err}" PARENT_SCOPE)
endfunction()

# the PNG of a run from a loaded binary is byte for byte the compiled run's
function(expect_same_image compiled_run loaded_run what)
  file(SHA256 "${SCRATCH}/${compiled_run}.png" compiled)
  file(SHA256 "${SCRATCH}/${loaded_run}.png" loaded)
  if(NOT compiled STREQUAL loaded)
    message(FATAL_ERROR "${loaded_run}: ${what}")
  endif()
endfunction()

# one entry each for wavetrace.cl and frame.cl, and no temporary files
function(expect_two_entries when)
  file(GLOB entries "${cache}/*")
  list(LENGTH entries count)
  if(NOT count EQUAL 2 OR NOT entries MATCHES "^[^;]*/[0-9a-f]+\\.bin;[^;]*/[0-9a-f]+\\.bin$")
    message(FATAL_ERROR "${when}: expected two entries and no temporary files in ${cache}, found: ${entries}")
  endif()
endfunction()

# empty cache: compiled and stored; then loaded
render(first "program wavetrace.cl: cache miss, compiled in [0-9.]+ s, binary [0-9.]+ MB.*program frame.cl: cache miss" ${cached})
expect_two_entries("after the first run")
render(second "program wavetrace.cl: cache hit, loaded [0-9.]+ MB in [0-9.]+ s.*program frame.cl: cache hit" ${cached})
# the loaded program renders the same image
expect_same_image(first second "the image from the cached binary differs from the compiled program's")

# two processes started together on an empty cache
file(REMOVE_RECURSE "${cache}")
string(REPLACE ";" " " args "${cached}")
execute_process(
  COMMAND sh -c "'${EXE}' render ${args} -o '${SCRATCH}/together_a.png' & a=$!
                 '${EXE}' render ${args} -o '${SCRATCH}/together_b.png' & b=$!
                 wait $a; ra=$?; wait $b; echo \"exit statuses $ra $?\""
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
message("together:\n${out}${err}")
if(NOT out MATCHES "exit statuses 0 0")
  message(FATAL_ERROR "together: expected both to succeed")
endif()
string(REGEX MATCHALL "program wavetrace.cl: cache miss" misses "${err}")
list(LENGTH misses miss_count)
if(NOT miss_count EQUAL 2)
  message(FATAL_ERROR "together: expected both processes to find the cache empty and compile")
endif()
if(NOT EXISTS "${SCRATCH}/together_a.png" OR NOT EXISTS "${SCRATCH}/together_b.png")
  message(FATAL_ERROR "together: an image is missing")
endif()
if("${err}" MATCHES "warning: kernel cache")
  message(FATAL_ERROR "together: a process found a damaged entry")
endif()
expect_two_entries("after two runs at once")
render(after_together "program wavetrace.cl: cache hit" ${cached})

# other build options: a miss, not the first entry; the frame program is the same
render(minimal "program wavetrace.cl: cache miss.*program frame.cl: cache hit" ${cached} --integrator minimal)
render(minimal_again "program wavetrace.cl: cache hit" ${cached} --integrator minimal)

# off: compiled, nothing stored
file(REMOVE_RECURSE "${cache}")
render(off "program wavetrace.cl: cache off" ${tiny} --kernel-cache off)
if(EXISTS "${cache}")
  message(FATAL_ERROR "off: the cache folder was created")
endif()

# The default folder (no folder chosen): on PoCL's CPU device the first run
# compiles without fetching the binary and hands the entries to a background
# `wavetrace store-programs` after the image is written; once they are
# stored, the next run loads them and renders the same image.
set(ENV{WAVETRACE_CACHE_DIR} "")
set(ENV{XDG_CACHE_HOME} "${SCRATCH}/xdg")
set(default_cache "${SCRATCH}/xdg/wavetrace/kernels")
render(default_first "program wavetrace.cl: cache miss" ${tiny})
if("${out}${err}" MATCHES "stored after the render, in the background")
  if(NOT "${out}${err}" MATCHES "2 program\\(s\\) handed to a background process")
    message(FATAL_ERROR "default_first: the deferred entries were not handed on")
  endif()
endif()
# the store runs at the lowest priority: give it time on a loaded machine
foreach(second RANGE 600)
  file(GLOB stored "${default_cache}/*.bin")
  file(GLOB pending "${default_cache}/*.pending")
  list(LENGTH stored stored_count)
  if(stored_count EQUAL 2 AND NOT pending)
    break()
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E sleep 1)
endforeach()
if(NOT stored_count EQUAL 2 OR pending)
  message(FATAL_ERROR "default folder: expected two entries and no pending store in ${default_cache}, found: ${stored} ${pending}")
endif()
render(default_second "program wavetrace.cl: cache hit.*program frame.cl: cache hit" ${tiny})
expect_same_image(default_first default_second "the image from the stored entry differs from the compiled program's")
