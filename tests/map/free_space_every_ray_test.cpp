// The scenes of tests/map/free_space_test.cpp (a vanished box, open ground with stereo noise, a
// ditch, the shadows of rocks, refused input, moves, snapshots, the switches) on the stack that
// casts every line of sight of each frame (WithEveryLineOfSight<CadreConfig>, free_space_rays =
// 65535: map/visibility/sight_table.hpp), with the same expectations but one.
#include "ccmap/map/visibility/sight_table.hpp"

#define CCMAP_FREE_SPACE_CONFIG ccmap::WithEveryLineOfSight<CadreConfig>
#define CCMAP_FREE_SPACE_RAYS ccmap::detail::kFreeSpaceEveryRay
#define FreeSpaceScenes FreeSpaceEveryRay
// The run marking of the sampled walk (the hidden cells between a rim and a proved drop-off) is
// not done for every line of sight: the ditch's first cells behind the rim stay unknown.
#define CCMAP_FREE_SPACE_NO_RUN_MARKING
#include "free_space_test.cpp"  // NOLINT(bugprone-suspicious-include): the same scenes, another stack
