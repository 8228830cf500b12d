// The scenes of tests/map/free_space_test.cpp on the stack whose viewshed table is fed by one
// point in 8 of each frame (WithEveryLineOfSight<CadreConfig>, free_space_rays =
// free_space_table_rays(8): map/visibility/sight_table.hpp), with the expectations of every line
// of sight (tests/map/free_space_every_ray_test.cpp). The camera has three times the scenes'
// pixels each way (360 x 270: 12,150 lines of sight a frame, a sixth of a CADRE frame's 69,000
// at this stride); at 120 x 90 (1,350) the box's and the ditch's sectors get too few rays.
#include "ccmap/map/visibility/sight_table.hpp"

#define CCMAP_FREE_SPACE_CONFIG ccmap::WithEveryLineOfSight<CadreConfig>
#define CCMAP_FREE_SPACE_RAYS ccmap::detail::free_space_table_rays(8)
#define FreeSpaceScenes FreeSpaceSampledTable
#define CCMAP_FREE_SPACE_CAMERA_SCALE 3
// As for every line of sight: the table does no run marking.
#define CCMAP_FREE_SPACE_NO_RUN_MARKING
#include "free_space_test.cpp"  // NOLINT(bugprone-suspicious-include): the same scenes, another stack
