# Debian libraries of the host tools (never of the flight core), each an INTERFACE or imported
# target the tools link:
#
#   ccmap_cli11   CLI11 (libcli11-dev, header only): the argument parsers of the CLI, the sim
#                 demo, the self-timed benchmark, the experiments and the traverse. Required
#                 wherever those are built, also for the cross-built benchmark (Debian's cross
#                 g++ searches /usr/include, where the headers are), with tools/args/parse_args.hpp.
#   GDAL          CCMAP_WITH_GDAL: the CLI's GeoTIFF output and --dem input (tools/io/raster_io.hpp)
#     AUTO (default)  ON when this is a host build with the tools and GDAL is found, else OFF
#                     (a status line says why; --geotiff and --dem are then refused, saying why)
#     ON              required: a missing GDAL stops the configure with the apt-get line (the
#                     host presets of CMakePresets.json)
#     OFF             not used
#   Sets CCMAP_GDAL_ENABLED.
set(CCMAP_CLI11_INCLUDE_DIR "/usr/include" CACHE PATH "CLI11 headers (Debian libcli11-dev): <dir>/CLI/CLI.hpp")
if(CCMAP_BUILD_TOOLS OR CCMAP_BUILD_BENCH)
  if(NOT EXISTS "${CCMAP_CLI11_INCLUDE_DIR}/CLI/CLI.hpp")
    message(FATAL_ERROR "CLI11 not found in ${CCMAP_CLI11_INCLUDE_DIR}: apt-get install libcli11-dev (or: tools/install-deps host)")
  endif()
  add_library(ccmap_cli11 INTERFACE)
  # tools/args/parse_args.hpp: how every tool runs its parser (help, one-line refusals, exit 2).
  target_include_directories(ccmap_cli11 INTERFACE ${PROJECT_SOURCE_DIR}/tools/args)
  # /usr/include is already searched (host and Debian cross g++); naming it again as -isystem
  # would reorder the system headers.
  if(NOT CCMAP_CLI11_INCLUDE_DIR STREQUAL "/usr/include")
    target_include_directories(ccmap_cli11 SYSTEM INTERFACE ${CCMAP_CLI11_INCLUDE_DIR})
  endif()
endif()

set(CCMAP_WITH_GDAL AUTO CACHE STRING
    "GeoTIFF output and raster DEM input of the ccmap CLI (GDAL): AUTO (when found on a host build), ON, OFF")
set_property(CACHE CCMAP_WITH_GDAL PROPERTY STRINGS AUTO ON OFF)
set(CCMAP_GDAL_ENABLED OFF)
string(TOUPPER "${CCMAP_WITH_GDAL}" _ccmap_gdal_mode)
set(_ccmap_gdal_apt "apt-get install libgdal-dev (or: tools/install-deps gdal)")
if(NOT _ccmap_gdal_mode STREQUAL "AUTO" AND NOT CCMAP_WITH_GDAL)
  message(STATUS "ccmap: GDAL off (CCMAP_WITH_GDAL=OFF): ccmap refuses --geotiff and --dem")
elseif(CMAKE_CROSSCOMPILING OR NOT CCMAP_BUILD_TOOLS)
  if(NOT _ccmap_gdal_mode STREQUAL "AUTO")
    message(FATAL_ERROR "CCMAP_WITH_GDAL=ON needs a host build with CCMAP_BUILD_TOOLS=ON")
  endif()
else()
  find_package(GDAL 3 QUIET)
  if(GDAL_FOUND)
    set(CCMAP_GDAL_ENABLED ON)
    message(STATUS "ccmap: GDAL ${GDAL_VERSION}: ccmap --geotiff and --dem")
  elseif(_ccmap_gdal_mode STREQUAL "AUTO")
    message(STATUS "ccmap: GDAL not found (${_ccmap_gdal_apt}): ccmap refuses --geotiff and --dem")
  else()
    message(FATAL_ERROR "CCMAP_WITH_GDAL=ON: GDAL not found: ${_ccmap_gdal_apt}")
  endif()
endif()
