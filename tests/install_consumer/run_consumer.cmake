# cmake -DEMF_BINARY_DIR=... -DCONSUMER_DIR=... -DWORK_DIR=... -DGENERATOR=... -P run_consumer.cmake
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "FAILED: ${ARGN}\n${out}\n${err}")
  endif()
  message("${out}")
endfunction()

run(${CMAKE_COMMAND} --install ${EMF_BINARY_DIR} --prefix ${prefix})
run(${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
    -DCMAKE_PREFIX_PATH=${prefix})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
set(ENV{LD_LIBRARY_PATH} "${prefix}/lib:$ENV{LD_LIBRARY_PATH}")
execute_process(COMMAND ${WORK_DIR}/build/consumer RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "FAILED: consumer exited ${rc}: ${out}")
endif()
message("consumer(cmake): ${out}")

# pkg-config
set(ENV{PKG_CONFIG_PATH} "${prefix}/lib/pkgconfig")
execute_process(COMMAND pkg-config --cflags --libs emf OUTPUT_VARIABLE flags RESULT_VARIABLE rc
                OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "FAILED: pkg-config emf")
endif()
separate_arguments(flags)
run(cc -std=c99 ${CONSUMER_DIR}/consumer.c ${flags} -o ${WORK_DIR}/consumer_pc)
execute_process(COMMAND ${WORK_DIR}/consumer_pc RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "FAILED: pkg-config consumer exited ${rc}: ${out}")
endif()
message("consumer(pkg-config): ${out}")

# The installed example builds standalone against the installed library and runs a tiny
# synthetic source through the runtime.
run(${CMAKE_COMMAND} -S ${prefix}/share/emf/examples -B ${WORK_DIR}/examples -G ${GENERATOR}
    -DCMAKE_PREFIX_PATH=${prefix})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/examples)
execute_process(COMMAND ${WORK_DIR}/examples/track_objects "synth:room?frames=2&width=64&height=48"
                        "map: {memory_mb: 16}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "end frames=2 produced=2 dropped=0")
  message(FATAL_ERROR "FAILED: installed example exited ${rc}: ${out}\n${err}")
endif()
message("example(installed): ${out}")

# Plugins by name come from the installation, not from the build tree that made it: the installed
# CLI (emf_internal linked in) and the installed library (through the example) both load them
# from <prefix>/lib/emf/plugins. (They looked in the configure-time prefix and the build tree.)
set(ENV{EMF_LOG_LEVEL} info)
execute_process(COMMAND ${prefix}/bin/emf run --quiet --source "synth:room?frames=2&width=64&height=48"
                        --set map.memory_mb=16 --detector nosuch --out ${WORK_DIR}/run-nosuch
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "  ${prefix}/lib/emf/plugins\n" OR
   err MATCHES "${EMF_BINARY_DIR}/plugins\n")
  message(FATAL_ERROR "FAILED: installed emf's plugin search path (exit ${rc}):\n${err}")
endif()
execute_process(COMMAND ${prefix}/bin/emf run --quiet --source "synth:cars?frames=2&width=64&height=48"
                        --set map.memory_mb=16 --detector motion --out ${WORK_DIR}/run-motion
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err MATCHES "loaded from ${prefix}/lib/emf/plugins/libemf_detector_motion.so")
  message(FATAL_ERROR "FAILED: installed emf --detector motion (exit ${rc}):\n${err}")
endif()
execute_process(COMMAND ${WORK_DIR}/examples/track_objects "synth:cars?frames=2&width=64&height=48"
                        "{map: {memory_mb: 16}, detector: {plugin: motion}}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err MATCHES "loaded from ${prefix}/lib/emf/plugins/libemf_detector_motion.so")
  message(FATAL_ERROR "FAILED: installed library's plugin lookup (exit ${rc}):\n${out}\n${err}")
endif()
message("plugins(installed): found in ${prefix}/lib/emf/plugins")

# The virtual OpenNI2 device from the prefix: the installed emf loads the installation's OpenNI2
# runtime folder (<libdir>/emf/openni2) through its RPATH. (The driver was installed where the
# system's libOpenNI2 never looks.)
if(EXISTS ${prefix}/lib/emf/openni2/OpenNI2/Drivers/libEmfVirtualDevice.so.0)
  run(${prefix}/bin/emf synth room --out ${WORK_DIR}/room --frames 2 --width 64 --height 48)
  execute_process(COMMAND ${prefix}/bin/emf run --quiet
                          --source "openni2:emf-virtual://${WORK_DIR}/room;speed=0"
                          --set map.memory_mb=16 --out ${WORK_DIR}/run-virtual
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "emf run: 2 frames")
    message(FATAL_ERROR "FAILED: installed emf on the virtual OpenNI2 device (exit ${rc}):\n${out}\n${err}")
  endif()
  message("openni2(installed): virtual device ran 2 frames")
endif()
