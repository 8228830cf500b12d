// ccmap_exp_fig6: Monte-Carlo obstacle detection against obstacle size, CCM (paper Fig. 6) and
// OMG with the roughness filter (Fig. 7), on simulated CADRE stereo over lunar terrain.
//   ccmap_exp_fig6 [--seed N] [--seeds A:B] [--out DIR] [--quick] [--paper-cell]   run trials, write a shard
//   ccmap_exp_fig6 --merge SHARD.csv SHARD.csv ... [--out DIR]          sum shards, table + plots
// A run writes <out>/fig6_shard_<A>_<B>.csv (integer counts) plus the table and plots of its own
// trials; --merge sums shards exactly (refusing overlapping seed ranges), so a campaign can be
// spread over processes or machines:
//   ccmap_exp_fig6 --seeds 1:21 & ccmap_exp_fig6 --seeds 21:41 & wait
//   ccmap_exp_fig6 --merge out/experiments/fig6_shard_1_21.csv out/experiments/fig6_shard_21_41.csv
// Without --seeds the trials are [seed, seed + default count). (ccmap_exp_fig6 --help lists the
// options: those of every experiment, common.hpp, the outlier gate's among them, and --seeds, --merge.)
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "experiments/common.hpp"
#include "experiments/detection.hpp"
#include "number_options.hpp"
#include "parse_args.hpp"

namespace {

/// "A:B" (base-10 whole numbers, B > A) into *a, *b; throws CLI::ValidationError otherwise.
void parse_seed_range(const std::string& s, std::uint64_t* a, std::uint64_t* b) {
  const std::size_t colon = s.find(':');
  const std::string why = "'" + s + "' is not A:B with B > A";
  if (colon == std::string::npos) throw CLI::ValidationError("--seeds", why);
  try {
    *a = ccmap::tools::parse_whole<std::uint64_t>("--seeds", s.substr(0, colon), 0, UINT64_MAX);
    *b = ccmap::tools::parse_whole<std::uint64_t>("--seeds", s.substr(colon + 1), 0, UINT64_MAX);
  } catch (const CLI::ValidationError&) {
    throw CLI::ValidationError("--seeds", why);
  }
  if (!(*b > *a)) throw CLI::ValidationError("--seeds", why);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app = make_experiment_app(
      "ccmap_exp_fig6", "Figs. 6/7: obstacle detection vs obstacle size, CCM vs OMG + roughness filter", &args);
  bool have_range = false;
  std::uint64_t seed_a = 0, seed_b = 0;
  app->add_option_function<std::string>(
         "--seeds",
         [&](const std::string& v) {
           parse_seed_range(v, &seed_a, &seed_b);
           have_range = true;
         },
         "the trials with seeds A .. B-1 (instead of --seed and the default count)")
      ->type_name("A:B");
  std::vector<std::string> merge_files;
  app->add_option("--merge", merge_files,
                  "sum these shards (written by runs) into <out>/fig6_merged.csv, with the\n"
                  "table and plots; runs no trials")
      ->type_name("SHARD.csv")
      ->expected(1, -1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      // CLI11 takes the first value whatever it looks like: "--merge --out DIR" would merge a
      // file named "--out". As before CLI11, a shard file does not start with "--".
      ->check(CLI::Validator(
          [](std::string& v) { return v.rfind("--", 0) == 0 ? "'" + v + "' is not a shard file" : std::string(); },
          ""));
  app->footer(
      "A run writes <out>/fig6_shard_<A>_<B>.csv (integer counts) plus the table and plots of its own\n"
      "trials; --merge sums shards exactly (refusing overlapping seed ranges), so a campaign can be\n"
      "spread over processes or machines (tools/campaign).");
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  const bool merge = !merge_files.empty();
  std::string error;
  if (!ensure_directory(args.out_dir, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }

  DetectionResult result;
  if (merge) {
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
