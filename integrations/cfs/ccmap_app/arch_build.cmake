# ccmap_app platform-scope configuration (evaluated at "make prep"): message IDs and sizes, each
# overridable by the mission like the headers of mission_build.cmake.
foreach(CCMAP_APP_CFGFILE ccmap_app_msgids.h ccmap_app_platform_cfg.h)
  generate_config_includefile(
    FILE_NAME     "${CCMAP_APP_CFGFILE}"
    FALLBACK_FILE "${CMAKE_CURRENT_LIST_DIR}/config/default_${CCMAP_APP_CFGFILE}")
endforeach()
