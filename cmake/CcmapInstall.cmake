# Installable package: `cmake --install` gives the public headers (include/ccmap/**, the platform
# header), the static libraries (ccmap_core and the platform library chosen by CCMAP_PLATFORM),
# a CMake package (find_package(ccmap) -> ccmap::core, with the platform resolved) and a
# pkg-config file ccmap.pc. The flight core has no third-party dependency a consumer needs: Eigen
# (header-only) is compiled into src/registration/ and appears in no installed header.
# examples/consumer builds against it; tools/check-install proves it for host and aarch64.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CCMAP_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/ccmap" CACHE STRING
    "Where ccmapConfig.cmake is installed (relative to the prefix)")
set(_ccmap_platform_target ccmap_platform_${CCMAP_PLATFORM})

# Exported names (namespace ccmap::): core, platform_<name>, platform_interface,
# core_build_flags (the warning wall; a link-only dependency of the static libraries, never
# applied to consumers).
set_target_properties(ccmap_core PROPERTIES EXPORT_NAME core)
set_target_properties(${_ccmap_platform_target} PROPERTIES EXPORT_NAME platform_${CCMAP_PLATFORM})
set_target_properties(ccmap_platform_interface PROPERTIES EXPORT_NAME platform_interface)
set_target_properties(ccmap_core_flags PROPERTIES EXPORT_NAME core_build_flags)
# The consumers' compile flags (-ffp-contract=off) are ccmap_core's PUBLIC options
# (src/CMakeLists.txt): exported with the target, as they reach an add_subdirectory consumer.

install(TARGETS ccmap_core ${_ccmap_platform_target} ccmap_platform_interface ccmap_core_flags
        EXPORT ccmapTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/ ${PROJECT_SOURCE_DIR}/platform/include/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h")
install(EXPORT ccmapTargets NAMESPACE ccmap:: DESTINATION ${CCMAP_INSTALL_CMAKEDIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ccmapConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/ccmapConfig.cmake
                              INSTALL_DESTINATION ${CCMAP_INSTALL_CMAKEDIR})
# 0.x: a minor version may change the API or the snapshot format.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ccmapConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ccmapConfig.cmake ${PROJECT_BINARY_DIR}/ccmapConfigVersion.cmake
        DESTINATION ${CCMAP_INSTALL_CMAKEDIR})

# pkg-config: relocatable (prefix from the .pc file's own directory).
file(RELATIVE_PATH _ccmap_pc_to_prefix "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
set(CCMAP_PC_PREFIX "\${pcfiledir}/${_ccmap_pc_to_prefix}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/ccmap.pc.in ${PROJECT_BINARY_DIR}/ccmap.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/ccmap.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
