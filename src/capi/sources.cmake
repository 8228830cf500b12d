target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/capi.cpp)

# The presets the C API instantiates: "all" (default), or a list of cadre, single_ccm,
# single_kalman, single_omg. A flight image takes one ("cadre": the text of the others is not
# linked); the calls answer CCMAP_INVALID_ARGUMENT for a preset left out (ccmap_preset_available).
set(CCMAP_CAPI_PRESETS "all" CACHE STRING "Presets the C API carries: all, or a ;-list of cadre single_ccm single_kalman single_omg")
set(_ccmap_capi_known cadre single_ccm single_kalman single_omg)
if(CCMAP_CAPI_PRESETS STREQUAL "all")
  set(_ccmap_capi_presets ${_ccmap_capi_known})
else()
  set(_ccmap_capi_presets ${CCMAP_CAPI_PRESETS})
endif()
foreach(_preset IN LISTS _ccmap_capi_presets)
  if(NOT _preset IN_LIST _ccmap_capi_known)
    message(FATAL_ERROR "CCMAP_CAPI_PRESETS: unknown preset '${_preset}' (known: all ${_ccmap_capi_known})")
  endif()
  string(TOUPPER "${_preset}" _preset_upper)
  set_property(SOURCE ${CMAKE_CURRENT_LIST_DIR}/capi.cpp APPEND PROPERTY COMPILE_DEFINITIONS CCMAP_CAPI_WITH_${_preset_upper}=1)
endforeach()
