# ccmap_app mission-scope configuration (evaluated at "make prep"). Each header is generated as a
# wrapper around config/default_<name>, so a mission overrides one by putting its own
# <name> in its *_defs folder, without editing this app.
foreach(CCMAP_APP_CFGFILE ccmap_app_topicids.h ccmap_app_fcncodes.h ccmap_app_msg.h ccmap_app_tbl.h)
  generate_config_includefile(
    FILE_NAME     "${CCMAP_APP_CFGFILE}"
    FALLBACK_FILE "${CMAKE_CURRENT_LIST_DIR}/config/default_${CCMAP_APP_CFGFILE}")
endforeach()
