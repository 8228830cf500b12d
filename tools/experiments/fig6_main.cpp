// ccmap_exp_fig6: Monte-Carlo obstacle detection against obstacle size, CCM (paper Fig. 6) and
// OMG with the roughness filter (Fig. 7), on simulated CADRE stereo over lunar terrain.
//   ccmap_exp_fig6 [--seed N] [--seeds A:B] [--out DIR] [--quick] [--paper-cell]   run trials, write a shard
//   ccmap_exp_fig6 --merge SHARD.csv SHARD.csv ... [--out DIR]          sum shards, table + plots
// A run writes <out>/fig6_shard_<A>_<B>.csv (integer counts) plus the table and plots of its own
// trials; --merge sums shards exactly (refusing overlapping seed ranges), so a campaign can be
// spread over processes or machines:
//   ccmap_exp_fig6 --seeds 1:21 & ccmap_exp_fig6 --seeds 21:41 & wait
//   ccmap_exp_fig6 --merge out/experiments/fig6_shard_1_21.csv out/experiments/fig6_shard_21_41.csv
// Without --seeds the trials are [seed, seed + default count).
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "experiments/common.hpp"
#include "experiments/detection.hpp"

namespace {

bool parse_range(const std::string& s, std::uint64_t* a, std::uint64_t* b) {
  const std::size_t colon = s.find(':');
  if (colon == std::string::npos) return false;
  // Named strings: `end` points into them, so they must outlive the checks of *end.
  const std::string first = s.substr(0, colon), second = s.substr(colon + 1);
  char* end = nullptr;
  *a = std::strtoull(first.c_str(), &end, 10);
  if (first.empty() || end == nullptr || *end != '\0') return false;
  *b = std::strtoull(second.c_str(), &end, 10);
  return !second.empty() && end != nullptr && *end == '\0' && *b > *a;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  // --seeds and --merge are this program's own flags; the rest goes to the common parser.
  std::vector<char*> rest{argv[0]};
  std::vector<std::string> merge_files;
  bool merge = false, have_range = false;
  std::uint64_t seed_a = 0, seed_b = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seeds" && i + 1 < argc) {
      if (!parse_range(argv[++i], &seed_a, &seed_b)) {
        std::fprintf(stderr, "bad --seeds value %s (want A:B with B > A)\n", argv[i]);
        return 2;
      }
      have_range = true;
    } else if (a == "--merge") {
      merge = true;
      while (i + 1 < argc && std::string(argv[i + 1]).rfind("--", 0) != 0) merge_files.push_back(argv[++i]);
    } else {
      rest.push_back(argv[i]);
    }
  }
  ExperimentArgs args;
  const int rc = parse_experiment_args(static_cast<int>(rest.size()), rest.data(),
                                       "Figs. 6/7: obstacle detection vs obstacle size, CCM vs OMG + roughness filter\n"
                                       "extra flags: --seeds A:B (trials with seeds A..B-1), --merge SHARD.csv...",
                                       &args);
  if (rc >= 0) return rc;
  std::string error;
  if (!ensure_directory(args.out_dir, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }

  DetectionResult result;
  if (merge) {
    if (merge_files.empty()) {
      std::fprintf(stderr, "--merge needs shard files\n");
      return 2;
    }
    std::vector<DetectionResult> shards;
    for (const std::string& f : merge_files) {
      DetectionResult s;
      if (!read_detection_csv(f, &s, &error)) {
        std::fprintf(stderr, "error: %s\n", error.c_str());
        return 1;
      }
      shards.push_back(s);
    }
    if (!merge_detection_results(shards, &result, &error)) {
      std::fprintf(stderr, "error: %s\n", error.c_str());
      return 1;
    }
    const std::string merged = args.out_dir + "/fig6_merged.csv";
    if (!write_detection_csv(merged, result, &error)) {
      std::fprintf(stderr, "error: %s\n", error.c_str());
      return 1;
    }
    std::printf("merged %zu shards into %s\n", shards.size(), merged.c_str());
  } else {
    DetectionConfig cfg = args.quick ? DetectionConfig::quick() : DetectionConfig{};
    cfg.first_seed = have_range ? seed_a : args.seed;
    cfg.gate = args.gate;
    cfg.paper_cell = args.paper_cell;
    if (have_range) cfg.trials = seed_b - seed_a;
    cfg.progress = true;
    result = run_detection(cfg);
    const std::string shard = args.out_dir + format("/fig6_shard_%llu_%llu.csv", static_cast<unsigned long long>(result.first_seed),
                                                    static_cast<unsigned long long>(result.end_seed));
    if (!write_detection_csv(shard, result, &error)) {
      std::fprintf(stderr, "error: %s\n", error.c_str());
      return 1;
    }
    std::printf("wrote shard %s\n", shard.c_str());
  }
  std::printf("Figs. 6/7: obstacle detection vs size (single-layer maps, CADRE stereo, lunar terrain)\n\n%s\n",
              detection_table(result).c_str());
  if (!write_detection_plots(result, args.out_dir, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  std::printf("wrote %s/fig6_ccm.svg, fig7_omg.svg, fig6_detection.svg\n", args.out_dir.c_str());
  return 0;
}
