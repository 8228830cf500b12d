// Explicit instantiation of Stack<CadreConfig> and of the planner queries over it under the
// core's flags (ccmap_core_flags: the warning wall, no exceptions, no RTTI,
// -fstack-usage/-fcallgraph-info with CCMAP_STACK_USAGE). The stack-usage test links these
// instances (extern template), so the frames it measures are the frames tools/stack-usage
// reports, and the lint sees the templates' code as the core compiles it. The paper-cell stack
// too, so that the warning wall and the lint see the 9-float branch.
#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/map/stack.hpp"

template class ccmap::Stack<ccmap::CadreConfig>;
template class ccmap::Stack<ccmap::PaperCell<ccmap::CadreConfig>>;
template ccmap::FootprintResult ccmap::query_footprint<ccmap::CadreConfig>(const ccmap::Stack<ccmap::CadreConfig>&,
                                                                          const ccmap::Footprint&) noexcept;
template ccmap::PathResult ccmap::query_path<ccmap::CadreConfig>(const ccmap::Stack<ccmap::CadreConfig>&,
                                                                const ccmap::PathPoint*, std::size_t,
                                                                const ccmap::PathSweep&) noexcept;
template ccmap::PathResult ccmap::query_arc<ccmap::CadreConfig>(const ccmap::Stack<ccmap::CadreConfig>&,
                                                               const ccmap::PathPose&, float, float,
                                                               const ccmap::PathSweep&) noexcept;
template ccmap::Status ccmap::fill_costmap<ccmap::CadreConfig>(const ccmap::Stack<ccmap::CadreConfig>&,
                                                              const ccmap::CostmapSpec&, std::uint8_t*, std::size_t,
                                                              ccmap::CostmapStats*) noexcept;
using PaperCadre = ccmap::PaperCell<ccmap::CadreConfig>;
template ccmap::FootprintResult ccmap::query_footprint<PaperCadre>(const ccmap::Stack<PaperCadre>&,
                                                                  const ccmap::Footprint&) noexcept;
template ccmap::PathResult ccmap::query_path<PaperCadre>(const ccmap::Stack<PaperCadre>&, const ccmap::PathPoint*,
                                                        std::size_t, const ccmap::PathSweep&) noexcept;
