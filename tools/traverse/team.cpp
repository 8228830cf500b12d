#include "traverse/team.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>

#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "experiments/canvas.hpp"
#include "experiments/common.hpp"
#include "layer_images.hpp"
#include "png.hpp"
#include "sim/path.hpp"
#include "sim/stereo.hpp"
#include "traverse/scene.hpp"

namespace ccmap::traverse {

namespace {

using experiments::format;
using experiments::Rgb;
using Exchange = MapExchange<CadreConfig>;

/// Rover r's path (about 13.5 m each): 1 the traverse (east, left turn, north); 2 north, left
/// turn, west; 3 south, left turn, east. They approach the middle of the terrain from three
/// sides and end within a few metres of each other.
std::vector<sim::PathPose> rover_path(int rover, double spacing_m) {
  const double kQuarter = 0.5 * sim::kPi;
  switch (rover) {
    case 2: return sim::generate_path(sim::Pose2{17.0, 6.0, kQuarter}, {{5.0, 0.0}, {3.5, kQuarter}, {4.0, 0.0}}, spacing_m);
    case 3: return sim::generate_path(sim::Pose2{6.0, 18.0, -kQuarter}, {{5.0, 0.0}, {3.5, kQuarter}, {4.0, 0.0}}, spacing_m);
    default: return sim::generate_path(sim::Pose2{6.0, 8.0, 0.0}, {{6.0, 0.0}, {3.5, kQuarter}, {4.0, 0.0}}, spacing_m);
  }
}

double cpu_ms(clock_t since) { return 1000.0 * static_cast<double>(std::clock() - since) / CLOCKS_PER_SEC; }

struct Rover {
  int id = 0;
  std::vector<sim::PathPose> path;
  std::unique_ptr<Map> alone = std::make_unique<Map>();
  std::unique_ptr<Map> team = std::make_unique<Map>();
  std::unique_ptr<Exchange> exchange = std::make_unique<Exchange>();
  RoverResult result;
};

Rgb class_rgb(CellClass c) {
  std::uint8_t v[3];
  tools::class_colour(to_string(c), v);
  return Rgb{v[0], v[1], v[2]};
}

/// Rows: rovers; columns: the final map alone and with the team (stack query classes), every
/// path drawn (the rover's own white, the others light blue), rovers as dots.
bool write_team_picture(const std::string& file, const std::vector<Rover>& rovers,
                        const std::vector<QueryRaster>& alone, const std::vector<QueryRaster>& team,
                        const std::vector<RoverResult>& results, std::string* error) {
  const int pix = alone.front().n;
  const int gap = 24, top = 40, row_gap = 44, legend = 50;
  const int rows = static_cast<int>(rovers.size());
  tools::RgbImage img(2 * pix + 3 * gap, top + rows * (pix + row_gap) + legend, 255);
  experiments::draw_text(img, gap, 10,
                         format("%d CADRE ROVERS, DELTAS EVERY FEW FRAMES: EACH ROVER'S FINAL MAP ALONE (LEFT) AND "
                                "WITH THE TEAM (RIGHT)",
                                rows),
                         experiments::kBlack);
  for (int r = 0; r < rows; ++r) {
    for (int col = 0; col < 2; ++col) {
      const QueryRaster& q = col == 0 ? alone[static_cast<std::size_t>(r)] : team[static_cast<std::size_t>(r)];
      const int left = gap + col * (pix + gap);
      const int y0 = top + r * (pix + row_gap) + 14;
      for (int j = 0; j < q.n; ++j) {
        for (int i = 0; i < q.n; ++i) {
          const std::size_t k = static_cast<std::size_t>(i) + static_cast<std::size_t>(q.n) * static_cast<std::size_t>(j);
          experiments::fill_rect(img, left + i, y0 + q.n - 1 - j, 1, 1, class_rgb(q.map_class[k]));
        }
      }
      auto px = [&](double x) { return left + (x - q.x0) / q.step; };
      auto py = [&](double y) { return y0 + q.n - (y - q.y0) / q.step; };
      for (const Rover& other : rovers) {
        const bool own = other.id == rovers[static_cast<std::size_t>(r)].id;
        if (!own && col == 0) continue;
        const Rgb colour = own ? Rgb{255, 255, 255} : Rgb{150, 200, 255};
        for (std::size_t i = 1; i < other.path.size(); ++i) {
          const sim::Pose2& a = other.path[i - 1].pose;
          const sim::Pose2& b = other.path[i].pose;
          experiments::draw_line(img, px(a.x), py(a.y), px(b.x), py(b.y), Rgb{20, 20, 160}, 4);
          experiments::draw_line(img, px(a.x), py(a.y), px(b.x), py(b.y), colour, 2);
        }
        const sim::Pose2& end = other.path.back().pose;
        experiments::fill_disc(img, px(end.x), py(end.y), 5.0, Rgb{20, 20, 160});
        experiments::fill_disc(img, px(end.x), py(end.y), 3.0, colour);
      }
      experiments::draw_rect(img, left - 1, y0 - 1, pix + 2, pix + 2, experiments::kBlack);
      const RoverResult& res = results[static_cast<std::size_t>(r)];
      const DetectionAreas& a = col == 0 ? res.alone : res.team;
      experiments::draw_text(img, left, y0 - 12,
                             format("ROVER %d %s: KNOWN %.0f M2, HAZARD FOUND %.1f M2%s", res.id,
                                    col == 0 ? "ALONE" : "WITH TEAM", a.known(), a.truth_hazard_known - a.missed,
                                    col == 0 ? "" : format(", SENT %.0f KB", 1e-3 * res.bytes_sent).c_str()),
                             experiments::kBlack);
      experiments::scale_bar(img, left + 10, y0 + pix - 16, 1.0 / q.step, 2.0, experiments::kBlack);
    }
  }
  const int ly = top + rows * (pix + row_gap) + 8;
  int x = gap;
  for (CellClass cc : {CellClass::kTraversable, CellClass::kObstacle, CellClass::kSteep, CellClass::kUnknown}) {
    x = experiments::legend_entry(img, x, ly, class_rgb(cc), to_string(cc));
  }
  experiments::draw_text(img, gap, ly + 18,
                         "GREY: UNKNOWN OR NEVER SEEN. PATHS: THE ROVER'S OWN WHITE, ITS TEAM MATES' LIGHT BLUE; DOTS: "
                         "FINAL POSITIONS. 20.5 M WINDOW, NORTH UP",
                         experiments::kBlack);
  return tools::write_png(file, img, error);
}

}  // namespace

TeamResult run_team(const TeamConfig& cfg) {
  TeamResult out;
  if (cfg.rovers < 2 || cfg.rovers > 3 || cfg.exchange_every < 1 || cfg.pixel_stride < 1 || !(cfg.frame_spacing_m > 0.0)) {
    out.error = "rovers must be 2 or 3, exchange_every, stride and spacing positive";
    return out;
  }
  std::vector<Rover> rovers(static_cast<std::size_t>(cfg.rovers));
  std::vector<std::vector<sim::PathPose>> paths;
  for (int r = 0; r < cfg.rovers; ++r) {
    Rover& rover = rovers[static_cast<std::size_t>(r)];
    rover.id = r + 1;
    rover.path = rover_path(rover.id, cfg.frame_spacing_m);
    rover.result.id = rover.id;
    rover.result.path_length_m = rover.path.back().distance_m;
    paths.push_back(rover.path);
  }
  const std::unique_ptr<sim::ProceduralTerrain> terrain = make_terrain(cfg.seed, paths);
  const sim::HeightRaster raster = sim::rasterize(*terrain, terrain->params().area, 0.01);
  sim::StereoParams sp;  // CADRE: 850 x 650, f 600 px, b 5 cm, 17.5 cm above ground
  sp.pixel_stride = cfg.pixel_stride;
  const sim::StereoCamera camera(sp);
  const StackParams params = default_stack_params(CadreConfig::kDefaultFinestCellWidthM);
  for (Rover& rover : rovers) {
    if (rover.alone->init(params) != Status::kOk || rover.team->init(params) != Status::kOk ||
        rover.exchange->init(*rover.team, ExchangeParams{static_cast<std::uint32_t>(rover.id), 1U, CellIndex{0, 0},
                                                         0.0F}) != Status::kOk) {
      out.error = "stack or exchange init failed";
      return out;
    }
  }
  std::vector<std::uint8_t> packet(cfg.packet_bytes > 0 ? cfg.packet_bytes : Exchange::max_delta_size());
  std::vector<sim::Pose2> at(rovers.size());  // each rover's last frame's pose
  // A drop-off the team map answers and the map alone does not: learned from a team mate.
  auto learned_drop = [&](Rover& rover, std::size_t step) {
    const sim::Pose2& pose = at[static_cast<std::size_t>(rover.id - 1)];
    double nearest = 1e9;
    std::size_t points = 0;
    for (double dx = -10.24; dx < 10.24; dx += 0.08) {
      for (double dy = -10.24; dy < 10.24; dy += 0.08) {
        const auto x = static_cast<float>(pose.x + dx), y = static_cast<float>(pose.y + dy);
        if (rover.team->query(x, y).cell_class == CellClass::kDropOff &&
            rover.alone->query(x, y).cell_class != CellClass::kDropOff) {
          ++points;
          nearest = std::min(nearest, std::hypot(dx, dy));
        }
      }
    }
    if (points > 0) {
      rover.result.first_learned_drop_frame = step;
      rover.result.first_learned_drop_range_m = nearest;
      rover.result.first_learned_drop_points = points;
    }
  };
  auto exchange_all = [&](std::size_t step) {
    for (Rover& sender : rovers) {
      std::size_t written = 0;
      ExportReport report{};
      const clock_t e0 = std::clock();
      if (sender.exchange->export_delta(packet.data(), packet.size(), ExportOptions{cfg.weight_floor, cfg.finest_layer}, &written,
                                        &report) != Status::kOk) {
        out.error = format("rover %d: export failed", sender.id);
        return;
      }
      sender.result.export_ms += cpu_ms(e0);
      ++sender.result.deltas_sent;
      sender.result.bytes_sent += written;
      sender.result.cells_sent += report.cells_written;
      sender.result.cells_saturated += report.cells_saturated;
      sender.result.cells_pending_at_end = report.cells_pending;
      sender.result.drops_sent += report.drops_written;
      sender.result.clears_sent += report.clears_written;
      std::size_t size = written;
      DeltaInfo info{};
      if (!cfg.free_space_exchange && Exchange::peek_delta(packet.data(), written, &info) == Status::kOk) {
        // The core alone, as a delta without entries: entry count 0, the core's CRC again.
        size = written - static_cast<std::size_t>(info.free_space_entries) * detail::kFreeSpaceEntryBytes;
        packet[6] = 0U;
        packet[7] = 0U;
        const std::uint32_t crc = crc32_update(0U, packet.data(), size - 4U);
        for (unsigned b = 0U; b < 4U; ++b) packet[size - 4U + b] = static_cast<std::uint8_t>(crc >> (8U * b));
      }
      for (Rover& receiver : rovers) {
        if (receiver.id == sender.id) continue;
        MergeReport merged{};
        const clock_t m0 = std::clock();
        const Status s = receiver.exchange->merge_delta(packet.data(), size, &merged);
        receiver.result.merge_ms += cpu_ms(m0);
        receiver.result.deltas_refused += s == Status::kOk ? 0U : 1U;
        receiver.result.cells_merged += merged.cells_merged;
        receiver.result.cells_outside += merged.cells_outside;
        receiver.result.drops_merged += merged.drops_merged;
        receiver.result.cells_cleared += merged.cells_cleared;
        receiver.result.clears_deferred += merged.clears_deferred;
        if (receiver.result.first_learned_drop_frame == 0U) {
          learned_drop(receiver, step);
        }
      }
      if (cfg.log != nullptr) {
        std::fprintf(cfg.log, "step %3zu  rover %d sends delta %u: %6zu bytes, %5u cells (%u saturated, %u pending)\n",
                     step, sender.id, report.sequence, written, report.cells_written, report.cells_saturated,
                     report.cells_pending);
      }
    }
  };
  std::size_t steps = 0;
  for (const Rover& rover : rovers) steps = std::max(steps, rover.path.size());
  std::vector<PointXYZ> points;
  for (std::size_t k = 0; k < steps && out.ok(); ++k) {
    for (Rover& rover : rovers) {
      if (k >= rover.path.size()) continue;
      const sim::Pose2& pose = rover.path[k].pose;
      at[static_cast<std::size_t>(rover.id - 1)] = pose;
      const sim::StereoFrame frame =
          camera.capture(raster, pose, pose, cfg.seed * 1000003ULL + static_cast<std::uint64_t>(rover.id) * 7919ULL + k);
      points.clear();
      for (const sim::Point3& p : frame.points_sensor) {
        points.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
      }
      const Pose sensor = camera_pose(camera, frame.sensor_position_map, pose.yaw);
      for (Map* map : {rover.alone.get(), rover.team.get()}) {
        if (map->move_to(static_cast<float>(pose.x), static_cast<float>(pose.y)) != Status::kOk ||
            map->update_frame_sensor(points.data(), points.size(), sensor, nullptr) != Status::kOk) {
          out.error = format("rover %d frame %zu refused", rover.id, k);
        }
      }
      ++rover.result.frames;
    }
    if ((k + 1) % static_cast<std::size_t>(cfg.exchange_every) == 0 || k + 1 == steps) {
      exchange_all(k + 1);
    }
  }
  if (!out.ok()) return out;

  std::vector<QueryRaster> alone_rasters, team_rasters;
  for (Rover& rover : rovers) {
    std::vector<LayerTruth> truths;
    for (int layer = 0; layer < Map::kLayerCount; ++layer) truths.push_back(layer_truth(*rover.team, *terrain, layer));
    alone_rasters.push_back(query_raster(*rover.alone, truths, cfg.query_step_m, &rover.result.alone));
    team_rasters.push_back(query_raster(*rover.team, truths, cfg.query_step_m, &rover.result.team));
    out.rovers.push_back(rover.result);
  }
  out.snapshot_bytes = snapshot_size<CadreConfig>();
  if (!cfg.out_dir.empty()) {
    std::string error;
    const std::string file = cfg.out_dir + "/team_alone_vs_team.png";
    if (!experiments::ensure_directory(cfg.out_dir, &error) ||
        !write_team_picture(file, rovers, alone_rasters, team_rasters, out.rovers, &error)) {
      out.error = error;
      return out;
    }
    out.pictures.push_back(file);
  }
  return out;
}

std::string team_report(const TeamResult& r, const TeamConfig& cfg) {
  using experiments::Table;
  Table t({"rover", "path", "frames", "known alone", "known with team", "hazard found alone", "with team",
           "false obstacle alone", "with team", "sent", "deltas", "cells sent (saturated)", "per delta",
           "merged cells (outside)", "export / merge CPU", "drop-off alone (false)", "with team (false)",
           "drops / clears sent", "drops merged, cleared (deferred)", "first drop learned: frame, range"});
  for (const RoverResult& v : r.rovers) {
    const double found_alone = v.alone.truth_hazard_known - v.alone.missed;
    const double found_team = v.team.truth_hazard_known - v.team.missed;
    t.add_row({format("%d", v.id), format("%.1f m", v.path_length_m), format("%d", v.frames),
               format("%.1f m2", v.alone.known()), format("%.1f m2 (%+.0f %%)", v.team.known(),
                                                          100.0 * (v.team.known() / std::max(v.alone.known(), 1e-9) - 1.0)),
               format("%.2f m2", found_alone), format("%.2f m2", found_team), format("%.2f m2", v.alone.false_obstacle),
               format("%.2f m2", v.team.false_obstacle), format("%.1f kB", 1e-3 * static_cast<double>(v.bytes_sent)),
               format("%zu", v.deltas_sent), format("%zu (%zu)", v.cells_sent, v.cells_saturated),
               format("%.1f kB", v.deltas_sent > 0 ? 1e-3 * static_cast<double>(v.bytes_sent) / static_cast<double>(v.deltas_sent) : 0.0),
               format("%zu (%zu)", v.cells_merged, v.cells_outside), format("%.0f / %.0f ms", v.export_ms, v.merge_ms),
               format("%.2f m2 (%.2f)", v.alone.drop_truth_hazard + v.alone.drop_truth_free, v.alone.drop_truth_free),
               format("%.2f m2 (%.2f)", v.team.drop_truth_hazard + v.team.drop_truth_free, v.team.drop_truth_free),
               format("%zu / %zu", v.drops_sent, v.clears_sent),
               format("%zu, %zu (%zu)", v.drops_merged, v.cells_cleared, v.clears_deferred),
               v.first_learned_drop_frame > 0
                   ? format("%zu, %.2f m (%zu points)", v.first_learned_drop_frame, v.first_learned_drop_range_m,
                            v.first_learned_drop_points)
                   : std::string("never")});
  }
  std::string out =
      format("%d rovers, seed %llu, stride %d, a frame every %.2f m, an exchange every %d frames%s%s%s; areas over "
             "each rover's final 20.48 m window (stack query every %.0f cm; truth per classifying layer)\n",
             cfg.rovers, static_cast<unsigned long long>(cfg.seed), cfg.pixel_stride, cfg.frame_spacing_m,
             cfg.exchange_every, cfg.weight_floor > 0.0F ? format(", weight floor %.0f", static_cast<double>(cfg.weight_floor)).c_str() : "",
             cfg.finest_layer > 0 ? format(", layers %d-4 only", cfg.finest_layer).c_str() : "",
             (std::string(cfg.packet_bytes > 0 ? format(", deltas of at most %zu bytes", cfg.packet_bytes).c_str() : "") +
              (cfg.free_space_exchange ? "" : ", deltas merged without their free-space entries")).c_str(),
             100.0 * cfg.query_step_m);
  out += t.str();
  out += format("(a whole CADRE snapshot is %zu bytes; hazard found = known truth-hazard area marked obstacle or steep)\n",
                r.snapshot_bytes);
  return out;
}

}  // namespace ccmap::traverse
