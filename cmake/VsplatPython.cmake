# The Python package (tools/python/vsplat, ctypes over libvsplat.so).
# Build tree: copied into BUILD/python/vsplat with a _paths.py naming this
# build's library, so PYTHONPATH=BUILD/python (or tools/python-user-site.sh,
# which the README's set-up runs) makes `import vsplat` work.
# Install: into VSPLAT_PYTHON_DIR (relative: under the prefix) with a
# _paths.py naming the installed library relative to the package, so the
# prefix stays relocatable.
set(VSPLAT_PYTHON_DIR "lib/python3/dist-packages" CACHE STRING
    "Where cmake --install puts the Python package vsplat (relative to the prefix, or absolute)")

file(GLOB VSPLAT_PY_SOURCES CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/tools/python/vsplat/*.py)
list(FILTER VSPLAT_PY_SOURCES EXCLUDE REGEX "/_paths\\.py$")
set(_vsplat_py_out)
foreach(_f ${VSPLAT_PY_SOURCES})
  get_filename_component(_n ${_f} NAME)
  add_custom_command(OUTPUT ${CMAKE_BINARY_DIR}/python/vsplat/${_n}
    COMMAND ${CMAKE_COMMAND} -E copy ${_f} ${CMAKE_BINARY_DIR}/python/vsplat/${_n} DEPENDS ${_f} VERBATIM)
  list(APPEND _vsplat_py_out ${CMAKE_BINARY_DIR}/python/vsplat/${_n})
endforeach()
add_custom_target(vsplat_python ALL DEPENDS ${_vsplat_py_out})
set(_vsplat_py_head "# Written by CMake (cmake/VsplatPython.cmake): where vsplat/_lib.py finds libvsplat.so.\n")
file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/python/vsplat/_paths.py
  CONTENT "${_vsplat_py_head}LIBRARY = \"$<TARGET_FILE:vsplat>\"\n")

if(IS_ABSOLUTE "${VSPLAT_PYTHON_DIR}")
  set(_vsplat_py_lib "${CMAKE_INSTALL_FULL_LIBDIR}")
else()
  file(RELATIVE_PATH _vsplat_py_lib "/${VSPLAT_PYTHON_DIR}/vsplat" "/${CMAKE_INSTALL_LIBDIR}")
  string(REGEX REPLACE "/$" "" _vsplat_py_lib "${_vsplat_py_lib}")
endif()
file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/python-install/_paths.py
  CONTENT "${_vsplat_py_head}LIBRARY = \"${_vsplat_py_lib}/$<TARGET_SONAME_FILE_NAME:vsplat>\"\n")
install(FILES ${VSPLAT_PY_SOURCES} ${CMAKE_BINARY_DIR}/python-install/_paths.py
  DESTINATION ${VSPLAT_PYTHON_DIR}/vsplat)
install(PROGRAMS tools/python/examples/render_colin27.py DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples)
