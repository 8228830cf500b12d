// ccmap_global_map: the global map of a patch directory as one GeoTIFF. Reads every patch of
// one CCM layer (files L<layer>_<tx>_<ty>.ccp, written by a PatchKeeper through
// posix_directory_storage), places each at its corrected pose (global_map.hpp) and writes the
// CLI's layer GeoTIFF (tools/io/raster_io.hpp: bands height, slope_x, slope_y, normal_var,
// class; no-data NaN). Bad patch files are named on stderr and skipped (exit code 3 then, 0 when
// every file was used, 1 for an I/O error, 2 for a refused command line).
//   ccmap_global_map --patches DIR --out FILE.tif [--layer L] [--uncorrected] [--epsg CODE]
#include <cstdio>
#include <string>

#include "global_map.hpp"
#include "number_options.hpp"
#include "parse_args.hpp"
#include "raster_io.hpp"

int main(int argc, char** argv) {
  std::string directory, out;
  int layer = 0, epsg = 0;
  bool uncorrected = false;
  CLI::App app("The global map of a patch directory as one GeoTIFF: the patches of one CCM layer placed at\n"
               "their corrected poses (a loop closure's re-stamping).",
               "ccmap_global_map");
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_option("--patches", directory, "the patch directory")->type_name("DIR")->required();
  app.add_option("--out", out, "the GeoTIFF written")->type_name("FILE")->required();
  ccmap::tools::add_whole(app, "--layer", &layer, 0, 7, "L", "the layer (default 0: the finest CCM layer)");
  app.add_flag("--uncorrected", uncorrected, "every patch at its writing pose (the map before stitching)");
  ccmap::tools::add_whole(app, "--epsg", &epsg, 0, 999999, "CODE", "coordinate system written (default: none)");
  if (const int code = ccmap::tools::parse_args(app, argc, argv); code >= 0) return code;
  std::string error, wkt;
  if (!ccmap::tools::raster_io_available()) {
    std::fprintf(stderr, "ccmap_global_map: %s\n", ccmap::tools::raster_io_unavailable_reason().c_str());
    return 2;
  }
  if (epsg != 0 && !ccmap::tools::srs_from_epsg(epsg, &wkt, &error)) {
    std::fprintf(stderr, "ccmap_global_map: %s\n", error.c_str());
    return 2;
  }
  std::vector<ccmap::tools::GlobalPatch> patches;
  ccmap::tools::PatchDirectoryCounts counts;
  if (!ccmap::tools::read_patch_directory(directory, layer, &patches, &counts, &error)) {
    std::fprintf(stderr, "ccmap_global_map: %s\n", error.c_str());
    return 1;
  }
  for (const std::string& name : counts.refused_names) {
    std::fprintf(stderr, "ccmap_global_map: %s refused (a check failed), skipped\n", name.c_str());
  }
  ccmap::tools::GlobalMapOptions options;
  options.apply_corrections = !uncorrected;
  ccmap::tools::GlobalRaster raster;
  ccmap::tools::LayerWindow extent;
  if (!ccmap::tools::assemble_global_map(patches, options, &raster, &error) ||
      !ccmap::tools::write_layer_geotiff(out, ccmap::tools::global_map_rows(raster, &extent), extent,
                                         raster.cell_width_m, wkt, &error)) {
    std::fprintf(stderr, "ccmap_global_map: %s\n", error.c_str());
    return 1;
  }
  std::printf("ccmap_global_map: layer %d, %d patches (%d refused, %d of a fine layer skipped), %lld cells placed, "
              "%d x %d pixels of %.3f m, %lld hazard pixels -> %s\n",
              layer, counts.used, counts.refused, counts.unsupported, static_cast<long long>(raster.cells_placed),
              raster.nx, raster.ny, raster.cell_width_m, static_cast<long long>(raster.hazard_pixels), out.c_str());
  return counts.refused > 0 ? 3 : 0;
}
