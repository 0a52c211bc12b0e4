# `cmake --install`: the kernel, the engine and the C++ client library as static archives with
# their headers under include/gatekeeper (as the sources name them: "kernel/...", "engine/..."),
# an exported CMake package (find_package(gatekeeper): gatekeeper::kernel, ::engine, ::client)
# and a pkg-config file; the daemon and the command-line clients under bin.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(GATEKEEPER_LIBRARIES gatekeeper_kernel gatekeeper_exact_volume gatekeeper_mesh_io gatekeeper_occt gatekeeper_p4
  gatekeeper_engine gatekeeper_proto gatekeeper_client)
install(TARGETS ${GATEKEEPER_LIBRARIES} gatekeeper_warnings EXPORT gatekeeperTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION include/gatekeeper)
foreach(lib kernel engine client)
  add_library(gatekeeper::${lib} ALIAS gatekeeper_${lib})
  set_target_properties(gatekeeper_${lib} PROPERTIES EXPORT_NAME ${lib})
endforeach()
install(TARGETS gatekeeperd gatekeeper-cli gatekeeper-mesh-check RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Public headers, as the sources include them.
foreach(dir kernel mesh_io occt_adapters machine_models engine clients/gatekeeper_client)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION include/gatekeeper/${dir}
    FILES_MATCHING PATTERN "*.h" PATTERN "internal" EXCLUDE)
endforeach()
install(FILES ${PROJECT_BINARY_DIR}/proto/gatekeeper/v1/gatekeeper.pb.h ${PROJECT_BINARY_DIR}/proto/gatekeeper/v1/gatekeeper.grpc.pb.h
  DESTINATION include/gatekeeper/gatekeeper/v1)
install(FILES ${PROJECT_SOURCE_DIR}/proto/gatekeeper/v1/gatekeeper.proto DESTINATION ${CMAKE_INSTALL_DATADIR}/gatekeeper/proto/gatekeeper/v1)

install(EXPORT gatekeeperTargets NAMESPACE gatekeeper:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/gatekeeper)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/gatekeeperConfig.cmake.in
  ${PROJECT_BINARY_DIR}/gatekeeperConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/gatekeeper)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/gatekeeperConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/gatekeeperConfig.cmake ${PROJECT_BINARY_DIR}/gatekeeperConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/gatekeeper)
configure_file(${PROJECT_SOURCE_DIR}/cmake/gatekeeper.pc.in ${PROJECT_BINARY_DIR}/gatekeeper.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/gatekeeper.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
