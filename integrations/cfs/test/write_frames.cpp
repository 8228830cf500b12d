// Writes the CADRE stereo frames of the project's simulator (tests/support/cadre_frames.hpp: the
// robot at the origin turning 0.1 rad per frame, 850 x 650 points) as the frame files ccmap_feed
// reads: a 64-byte header in this machine's byte order (magic "CCF1", uint32 point count, float
// rotation[9] row-major and translation[3] of the sensor pose, 8 spare bytes), then the
// sensor-frame points, 3 floats each.
//   write_frames OUT_DIR COUNT   ->  OUT_DIR/frame0.bin .. frame<COUNT-1>.bin
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "support/cadre_frames.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: write_frames OUT_DIR COUNT\n");
    return 2;
  }
  const int count = std::atoi(argv[2]);
  for (int k = 0; k < count; ++k) {
    const ccmap::test::CadreFrame frame = ccmap::test::make_cadre_frame(ccmap::test::cadre_sequence_spec(k));
    unsigned char header[64] = {};
    const std::uint32_t n = static_cast<std::uint32_t>(frame.sensor_points.size());
    float pose[12];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        pose[3 * r + c] = frame.pose.rotation[r][c];
      }
    }
    pose[9] = frame.pose.translation.x;
    pose[10] = frame.pose.translation.y;
    pose[11] = frame.pose.translation.z;
    std::memcpy(header, "CCF1", 4);
    std::memcpy(header + 4, &n, sizeof n);
    std::memcpy(header + 8, pose, sizeof pose);
    const std::string path = std::string(argv[1]) + "/frame" + std::to_string(k) + ".bin";
    std::FILE* out = std::fopen(path.c_str(), "wb");
    if (out == nullptr) {
      std::perror(path.c_str());
      return 1;
    }
    bool ok = std::fwrite(header, 1, sizeof header, out) == sizeof header;
    for (const ccmap::PointXYZ& p : frame.sensor_points) {
      const float xyz[3] = {p.x, p.y, p.z};
      ok = ok && std::fwrite(xyz, sizeof(float), 3, out) == 3;
    }
    ok = (std::fclose(out) == 0) && ok;
    if (!ok) {
      std::fprintf(stderr, "write_frames: cannot write %s\n", path.c_str());
      return 1;
    }
  }
  return 0;
}
