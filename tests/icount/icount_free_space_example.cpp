// Instruction counts of free space from lines of sight (docs/performance.md, "Free space: what
// it costs"): two CADRE stacks follow the flight cycle's drive (tests/support/flight_cycle.hpp:
// full 850 x 650 frames with 2 % NaN and 6 % far points, 0.25 m apart), one with free space at
// its CADRE default, one with it off (free_space_rays = 0). Each frame is given once in the
// sensor frame and once, to two more stacks, in the map frame. Regions
// (tests/support/icount_marker.hpp):
//   1  update_frame_sensor, free space on     2  update_frame_sensor, free space off
//   3  update_frame (map frame), on           4  update_frame (map frame), off
// Region 1 minus region 2 is the stage's cost per frame; the program prints the lines of sight
// walked, so the cost per ray follows. On other targets the markers are empty and the program
// checks that every call succeeds and that the stage walked rays.
//
//   icount_free_space_example [frames width_px height_px [rays]]   default: 2 80 50, the CADRE
//   default's lines of sight (3 850 650: the figures of docs/performance.md; `rays` measures the
//   stage at another free_space_rays, 1..65535; 65535: every line of sight, the viewshed table,
//   on the stack that carries it, WithEveryLineOfSight<CadreConfig>; 65536 - k for k = 2, 4, 8,
//   16: the table fed by every k-th point, detail::free_space_table_rays(k))
#include <cstdint>
#include <cstdio>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "support/count_arg.hpp"
#include "support/flight_cycle.hpp"
#include "support/icount_marker.hpp"

namespace {

template <typename Map>
int run(int frames, int width_px, int height_px, int rays_per_frame) {
  // On the heap, as the timing test and icount_stack_example (the counts are of the same code).
  auto sensor_on = std::make_unique<Map>();
  auto sensor_off = std::make_unique<Map>();
  auto map_on = std::make_unique<Map>();
  auto map_off = std::make_unique<Map>();
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  if (rays_per_frame > 0) {
    params.free_space_rays = static_cast<float>(rays_per_frame);
  }
  if (!(params.free_space_rays > 0.0F) || sensor_on->init(params) != ccmap::Status::kOk ||
      map_on->init(params) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_free_space_example: the CADRE default should have free space on\n");
    return 1;
  }
  const float params_on_rays = params.free_space_rays;
  params.free_space_rays = 0.0F;
  if (sensor_off->init(params) != ccmap::Status::kOk || map_off->init(params) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_free_space_example: init failed\n");
    return 1;
  }
  std::uint64_t rays[2] = {0, 0}, refused[2] = {0, 0}, cleared = 0, drops = 0;
  for (int k = 0; k < frames; ++k) {
    const ccmap::test::CadreFrame f = ccmap::test::cycle_frame(k, width_px, height_px);
    const ccmap::test::CyclePose pose = ccmap::test::cycle_pose(k);
    const std::size_t n = f.map_points.size();
    for (Map* m : {sensor_on.get(), sensor_off.get(), map_on.get(), map_off.get()}) {
      if (m->move_to(pose.x, pose.y) != ccmap::Status::kOk) {
        std::fprintf(stderr, "icount_free_space_example: move %d refused\n", k);
        return 1;
      }
    }
    ccmap::FrameCounters a{}, b{}, c{}, d{};
    ccmap::test::icount_begin<1>();
    const ccmap::Status sa = sensor_on->update_frame_sensor(f.sensor_points.data(), n, f.pose, &a);
    ccmap::test::icount_end<1>();
    ccmap::test::icount_begin<2>();
    const ccmap::Status sb = sensor_off->update_frame_sensor(f.sensor_points.data(), n, f.pose, &b);
    ccmap::test::icount_end<2>();
    ccmap::test::icount_begin<3>();
    const ccmap::Status sc = map_on->update_frame(f.map_points.data(), n, f.sensor_origin, &c);
    ccmap::test::icount_end<3>();
    ccmap::test::icount_begin<4>();
    const ccmap::Status sd = map_off->update_frame(f.map_points.data(), n, f.sensor_origin, &d);
    ccmap::test::icount_end<4>();
    if (sa != ccmap::Status::kOk || sb != ccmap::Status::kOk || sc != ccmap::Status::kOk ||
        sd != ccmap::Status::kOk || a.free_rays == 0U || c.free_rays == 0U || b.free_rays != 0U ||
        d.free_rays != 0U || a.received != n || c.received != n) {
      std::fprintf(stderr, "icount_free_space_example: frame %d: rays %u/%u (on) %u/%u (off)\n", k, a.free_rays,
                   c.free_rays, b.free_rays, d.free_rays);
      return 1;
    }
    rays[0] += a.free_rays;
    rays[1] += c.free_rays;
    refused[0] += a.free_rays_refused;
    refused[1] += c.free_rays_refused;
    cleared += a.cleared_cells + c.cleared_cells;
    drops += a.drop_cells + c.drop_cells;
  }
  std::printf("icount_free_space_example: %d frames of %d x %d points, %d rays per frame; lines of sight walked %llu (sensor frame), "
              "%llu (map frame); refused %llu, %llu; cells cleared %llu, drop-offs %llu\n",
              frames, width_px, height_px, static_cast<int>(params_on_rays), static_cast<unsigned long long>(rays[0]),
              static_cast<unsigned long long>(rays[1]), static_cast<unsigned long long>(refused[0]),
              static_cast<unsigned long long>(refused[1]), static_cast<unsigned long long>(cleared),
              static_cast<unsigned long long>(drops));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 2, width_px = 80, height_px = 50, rays_per_frame = 0;
  if (argc != 1 && ((argc != 4 && argc != 5) || !ccmap::test::parse_count(argv[1], 1000, &frames) ||
                    !ccmap::test::parse_count(argv[2], 4000, &width_px) ||
                    !ccmap::test::parse_count(argv[3], 4000, &height_px) ||
                    (argc == 5 && !ccmap::test::parse_count(argv[4], 65535, &rays_per_frame)))) {
    std::fprintf(stderr, "usage: icount_free_space_example [frames width_px height_px [rays]]\n");
    return 2;
  }
  if (ccmap::detail::sight_stride_of_rays(static_cast<float>(rays_per_frame)) > 0) {
    return run<ccmap::Stack<ccmap::WithEveryLineOfSight<ccmap::CadreConfig>>>(frames, width_px, height_px,
                                                                              rays_per_frame);
  }
  return run<ccmap::Stack<ccmap::CadreConfig>>(frames, width_px, height_px, rays_per_frame);
}
