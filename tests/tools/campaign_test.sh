#!/usr/bin/env bash
# A tiny Fig. 6/7 campaign (3 seeds, --quick) three ways, all of which must give exactly the
# one-process result (same CSV, same table, same plots, byte for byte):
#   1. tools/campaign/run-local: 3 shards through GNU parallel, then --merge;
#   2. tools/campaign/fig6.sbatch run as Slurm runs an array job (SLURM_ARRAY_TASK_ID = 0, 1, 2
#      in the environment; Slurm itself is not installed here), then its merge step;
#   3. the reference: one process with --seeds 1:4.
# Also: the merge step refuses a campaign with a missing shard.
#   campaign_test.sh <ccmap_exp_fig6> <source dir> <work dir>
set -euo pipefail
exe=$1 root=$2 work=$3
command -v parallel >/dev/null || { echo "skipped: GNU parallel is not installed (tools/install-deps python)"; exit 77; }
rm -rf "$work" && mkdir -p "$work/one"

"$exe" --quick --seeds 1:4 --out "$work/one" >"$work/one/stdout.txt"
"$root/tools/campaign/run-local" --exe "$exe" --seeds 1:4 --shards 3 --jobs 2 --out "$work/local" -- --quick
for task in 0 1 2; do
  SLURM_ARRAY_TASK_ID=$task SLURM_SUBMIT_DIR=$work CCMAP_SEEDS_PER_TASK=1 CCMAP_CAMPAIGN_OUT="$work/slurm" \
    CCMAP_FIG6="$exe" "$root/tools/campaign/fig6.sbatch" --quick >/dev/null
done
CCMAP_SEEDS_PER_TASK=1 CCMAP_CAMPAIGN_OUT="$work/slurm" CCMAP_FIG6="$exe" \
  "$root/tools/campaign/fig6.sbatch" merge >"$work/slurm/merge.txt"

status=0
table() { sed -n '/^Figs\. 6\/7/,$p' "$1" | grep -v '^wrote '; }  # the table, without output paths
for campaign in local slurm; do
  for f in fig6_ccm.svg fig7_omg.svg fig6_detection.svg; do
    cmp "$work/one/$f" "$work/$campaign/$f" || status=1
  done
  cmp "$work/one/fig6_shard_1_4.csv" "$work/$campaign/fig6_merged.csv" || status=1
  diff <(table "$work/one/stdout.txt") <(table "$work/$campaign/merge.txt") || status=1
  [ "$(table "$work/one/stdout.txt" | wc -l)" -gt 5 ] || { echo "no table in the one-process output"; status=1; }
done

# A missing middle shard: the Slurm merge step refuses instead of merging a partial campaign.
rm -r "$work/slurm/shard_2_3"
if CCMAP_SEEDS_PER_TASK=1 CCMAP_CAMPAIGN_OUT="$work/slurm" CCMAP_FIG6="$exe" \
     "$root/tools/campaign/fig6.sbatch" merge >/dev/null 2>"$work/slurm/refusal.txt"; then
  echo "the merge accepted a campaign with seed 2 missing"; status=1
fi
grep -q "expected a shard from seed 2" "$work/slurm/refusal.txt" || { cat "$work/slurm/refusal.txt"; status=1; }
[ "$status" -eq 0 ] && echo "campaign: run-local and the Slurm array script equal the one-process run"
exit "$status"
