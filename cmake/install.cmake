# cmake --install: the runtime's libraries and headers, the chladni command, CMake package files
# (find_package(Chladni): Chladni::chladni, the shared C library; Chladni::core, ::gpu,
# ::runtime, ::capi, the static ones) and pkg-config files (chladni: the shared library;
# chladni-static: the static ones). The
# precompute library (TetGen, CGAL, hmat-oss) is not installed: engines link the runtime only.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CHLADNI_EXPORTED chladni_core chladni_gpu chladni_kernels chladni_runtime chladni_capi)
foreach(t ${CHLADNI_EXPORTED})
  string(REPLACE "chladni_" "" short ${t})
  set_target_properties(${t} PROPERTIES EXPORT_NAME ${short})
endforeach()
set_target_properties(chladni_shared PROPERTIES EXPORT_NAME chladni)
install(TARGETS ${CHLADNI_EXPORTED} chladni_shared EXPORT ChladniTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS chladni RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY core/include/ gpu/include/ runtime/include/ runtime/capi/include/
                  ${PROJECT_BINARY_DIR}/core/generated_public/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

set(CHLADNI_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/Chladni)
install(EXPORT ChladniTargets NAMESPACE Chladni:: DESTINATION ${CHLADNI_CMAKE_DIR})
configure_package_config_file(cmake/ChladniConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/ChladniConfig.cmake
                              INSTALL_DESTINATION ${CHLADNI_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ChladniConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ChladniConfig.cmake
              ${PROJECT_BINARY_DIR}/ChladniConfigVersion.cmake
        DESTINATION ${CHLADNI_CMAKE_DIR})

# Relocatable: the prefix is found from the .pc file's own folder (cmake --install --prefix).
file(RELATIVE_PATH CHLADNI_PC_TO_PREFIX ${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig
     ${CMAKE_INSTALL_PREFIX})
string(REGEX REPLACE "/$" "" CHLADNI_PC_TO_PREFIX "${CHLADNI_PC_TO_PREFIX}")
configure_file(cmake/chladni.pc.in ${PROJECT_BINARY_DIR}/chladni.pc @ONLY)
configure_file(cmake/chladni-static.pc.in ${PROJECT_BINARY_DIR}/chladni-static.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/chladni.pc ${PROJECT_BINARY_DIR}/chladni-static.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
