# One static library per module (a folder of src/, and firmware_host/), named emf_<module>.
# DEPENDS lists the modules it may include and call: the allowed direction of the layers
# (docs/architecture.md). tests/layering checks every #include against these lists and fails
# on an include of an undeclared module and on any cycle between modules.

# Third-party libraries and the definitions every module compiles with.
add_library(emf_third_party INTERFACE)
target_include_directories(emf_third_party INTERFACE ${PROJECT_SOURCE_DIR}/src ${PROJECT_SOURCE_DIR}
                                                     ${PROJECT_SOURCE_DIR}/include)
target_include_directories(emf_third_party SYSTEM INTERFACE ${OpenCV_INCLUDE_DIRS})
target_compile_definitions(emf_third_party INTERFACE CL_TARGET_OPENCL_VERSION=120
                                                     CL_USE_DEPRECATED_OPENCL_1_2_APIS
                                                     EMF_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                                                     EMF_INSTALL_DATADIR="${CMAKE_INSTALL_FULL_DATADIR}")
target_link_libraries(emf_third_party INTERFACE OpenCL::OpenCL Eigen3::Eigen ${OpenCV_LIBS}
                                                yaml-cpp nlohmann_json::nlohmann_json
                                                Threads::Threads ZLIB::ZLIB ${CMAKE_DL_LIBS})

# emf_add_module(<module> SOURCES <files>... [DEPENDS <module>...])
function(emf_add_module module)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS" ${ARGN})
  set(target emf_${module})
  add_library(${target} STATIC ${ARG_SOURCES})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON
                                             CXX_VISIBILITY_PRESET hidden
                                             VISIBILITY_INLINES_HIDDEN ON)
  target_link_libraries(${target} PUBLIC emf_third_party)
  foreach(dep IN LISTS ARG_DEPENDS)
    if(NOT dep STREQUAL "api")  # headers only, on every module's include path
      target_link_libraries(${target} PUBLIC emf_${dep})
    endif()
  endforeach()
  emf_set_warnings(${target})
  emf_module_graph_entry(${module} DEPENDS ${ARG_DEPENDS})
endfunction()

# emf_module_graph_entry(<module> [DIR <folder>] [DEPENDS <module>...]): records a module of the
# layering graph without building a library (the C API in libemf, the tools). DIR defaults to
# the current source folder; the last component of the folder is its include prefix.
function(emf_module_graph_entry module)
  cmake_parse_arguments(ARG "" "DIR" "DEPENDS" ${ARGN})
  if(NOT ARG_DIR)
    set(ARG_DIR ${CMAKE_CURRENT_SOURCE_DIR})
  endif()
  file(RELATIVE_PATH dir ${PROJECT_SOURCE_DIR} ${ARG_DIR})
  set_property(GLOBAL APPEND PROPERTY EMF_MODULES ${module})
  set_property(GLOBAL PROPERTY EMF_MODULE_DEPENDS_${module} "${ARG_DEPENDS}")
  set_property(GLOBAL PROPERTY EMF_MODULE_DIR_${module} "${dir}")
endfunction()

# Writes <file>: one line per module, "<module> <folder> <direct dependencies...>", read by the
# layering test. Called once every module is declared.
function(emf_write_module_graph file)
  get_property(modules GLOBAL PROPERTY EMF_MODULES)
  set(text "")
  foreach(module IN LISTS modules)
    get_property(deps GLOBAL PROPERTY EMF_MODULE_DEPENDS_${module})
    get_property(dir GLOBAL PROPERTY EMF_MODULE_DIR_${module})
    string(REPLACE ";" " " deps "${deps}")
    string(APPEND text "${module} ${dir} ${deps}\n")
  endforeach()
  file(WRITE ${file} "${text}")
endfunction()

# The public C API headers (include/emf/): plain C, usable from every module.
emf_module_graph_entry(api DIR ${PROJECT_SOURCE_DIR}/include/emf)
