// Explicit instantiation of Stack<CadreConfig> under the core's flags (ccmap_core_flags: the
// warning wall, no exceptions, no RTTI, -fstack-usage/-fcallgraph-info with CCMAP_STACK_USAGE).
// The stack-usage test links this instance (extern template), so the frames it measures are the
// frames tools/stack-usage reports, and the lint sees the template's code as the core compiles it.
// The paper-cell stack too, so that the warning wall and the lint see the 9-float branch.
#include "ccmap/map/stack.hpp"

template class ccmap::Stack<ccmap::CadreConfig>;
template class ccmap::Stack<ccmap::PaperCell<ccmap::CadreConfig>>;
