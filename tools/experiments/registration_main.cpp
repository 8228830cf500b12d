// ccmap_exp_registration: registration's error against an injected pose error on real terrain
// (the Lone Star scan, the Mars DTM: skipped without ../shared/data) and where it fails (flat
// ground, a sinusoid), as a function of overlap and offset (experiments/registration.hpp).
//   ccmap_exp_registration [--seed N] [--out DIR] [--quick] [--data DIR]
// (ccmap_exp_registration --help lists the options.)
#include <cstdio>
#include <string>

#include "experiments/common.hpp"
#include "experiments/registration.hpp"
#include "parse_args.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app = make_experiment_app(
      "ccmap_exp_registration", "Registration against injected pose errors on real and synthetic terrain", &args);
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  RegistrationExpConfig cfg = args.quick ? RegistrationExpConfig::quick() : RegistrationExpConfig{};
  cfg.seed = args.seed;
  cfg.data_dir = args.data_dir;
  const RegistrationExpResult r = run_registration_experiment(cfg);
  std::printf("Registration against injected pose errors (%d trials per cell; Stack<SingleCcmConfig>, default\n"
              "parameters with a search of 1.5 x the largest offset and 40 iterations)\n\n%s",
              cfg.trials, registration_table(r).c_str());
  std::string error;
  if (!write_registration_outputs(r, args.out_dir, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  std::printf("wrote %s/registration.csv and registration_<terrain>.svg\n", args.out_dir.c_str());
  return 0;
}
