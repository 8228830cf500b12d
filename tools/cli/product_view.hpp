// 'ccmap product': a map product (include/ccmap/product/product_format.hpp; what ccmap_publish
// writes and a ground station receives) checked, printed and drawn. Host tool code.
#pragma once

#include <ostream>
#include <string>

namespace ccmap::tools {

/// Reads the product file `path`, checks it with the library's standalone decoder and prints its
/// header (one "key value" line per field, docs/icd.md names), the cells per class and status,
/// and with `cells` every cell ("ix iy class cost status layer height_m inclination"). With a
/// non-empty png_prefix also writes <prefix>_class.png, <prefix>_cost.png and <prefix>_height.png
/// (north up, unknown cells grey / 255 / black). Returns the exit code: 0, or 1 with a message in
/// *error (unreadable file, not a whole product, a picture not written).
int view_product(const std::string& path, bool cells, const std::string& png_prefix, std::ostream& out,
                 std::string* error);

}  // namespace ccmap::tools
