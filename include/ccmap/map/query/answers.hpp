// Answers of a stack's layers to point queries: the (pooled) CCM cell's surface at the query
// point, the piece-wise constant cell's height, classes (paper Sections IV-D, IV-E), the
// roughness filter baseline of the constant layer. A QueryView is a read-only view (three
// references) that Stack's queries and exports use; integrators need not read it.
#pragma once

#include <cmath>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/map/classify.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/query/pooling.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/visibility/free_space_cell.hpp"

namespace ccmap::detail {

/// The free-space records a query reads for drop-offs (map/visibility/free_space.hpp): one record
/// grid per layer, or nullptr (a stack without free space: no drop-offs), and each layer's record
/// checks (integrity.hpp: checks[layer][slot] belongs to the record of buffer slot `slot`).
struct DropRecords {
  const RingGrid<FreeSpaceCell>* layer[kMaxLayers]{};
  const CellCheck* checks[kMaxLayers]{};
};

[[nodiscard]] inline QueryResult empty_result(Status status, int layer) noexcept {
  return QueryResult{status, layer, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, CellClass::kUnknown, false};
}

/// The answer of a place whose answering cell is distrusted (map/detail/integrity.hpp,
/// "distrust"): kUnknown at `layer`, upset set.
[[nodiscard]] inline QueryResult upset_result(int layer) noexcept {
  QueryResult r = empty_result(Status::kUnknown, layer);
  r.upset = true;
  return r;
}

template <typename Config>
class QueryView {
 public:
  using Layers = LayerSet<Config>;
  using FineCell = typename Layers::FineCell;

  QueryView(const Layers& layers, const StackParams& params, const float* thresholds,
            const DropRecords* drops = nullptr) noexcept
      : layers_(layers), params_(params), thresholds_(thresholds), drops_(drops) {}

  /// Answer from the finest layer that knows (x, y), a drop-off counting as known at its layer (an
  /// unobserved cell, no finer point below it, that lines of sight proved a drop-off: finer
  /// knowledge than a coarser cell that holds the ground beside it); see Stack::query. A
  /// distrusted answer (upset) ends the search: no coarser layer answers for a place whose cell
  /// lost what it knew.
  [[nodiscard]] QueryResult query(float x, float y) const noexcept {
    QueryResult result = empty_result(Status::kOutsideMap, -1);
    for (int layer = 0; layer < Layers::kLayerCount; ++layer) {
      CellIndex index{};
      if (!layers_.locate(layer, x, y, &index)) {
        continue;
      }
      if (result.status == Status::kOutsideMap) {
        result = empty_result(Status::kUnknown, layer);
      }
      QueryResult answer = answer_at(layer, index, x, y, true);
      if (answer.status != Status::kOk) {
        if (answer.upset) {
          return answer;
        }
        continue;
      }
      if (!Layers::is_ccm(layer) && Layers::kCcmLayerCount > 0 && answer.cell_class != CellClass::kDropOff) {
        refine_with_ccm(x, y, answer);
      }
      return answer;
    }
    return result;
  }

  /// True if the cell of `layer` at `index` (inside the window) holds no point of its own and
  /// its free-space record makes it a drop-off. A record whose bits disagree with its check is
  /// no evidence (no drop-off; the scrub resets and counts it).
  [[nodiscard]] bool unobserved_drop(int layer, CellIndex index) const noexcept {
    if (drops_ == nullptr || drops_->layer[layer] == nullptr || drops_->checks[layer] == nullptr) {
      return false;
    }
    const float weight = Layers::is_ccm(layer) ? layers_.ccm_grid(layer).cell_unchecked(index).weight
                                               : fine_weight(index);
    if (weight > 0.0F) {
      return false;
    }
    const RingGrid<FreeSpaceCell>& grid = *drops_->layer[layer];
    const FreeSpaceCell& rec = grid.cell_unchecked(index);
    return is_drop(rec) && cell_signature(rec) == drops_->checks[layer][static_cast<std::size_t>(&rec - grid.storage())];
  }

  /// The answer of an unobserved drop-off cell: kOk, class kDropOff, weight 0, height the upper
  /// bound the rays proved (the terrain lies at or below it), every other number 0.
  [[nodiscard]] QueryResult drop_answer(int layer, CellIndex index) const noexcept {
    QueryResult out = empty_result(Status::kOk, layer);
    out.cell_width_m = layers_.widths[layer];
    const FreeSpaceCell& rec = drops_->layer[layer]->cell_unchecked(index);
    out.height_m = has_bound(rec) ? bound_m(rec) : 0.0F;
    out.cell_class = CellClass::kDropOff;
    return out;
  }

  /// The answer of `layer` at `index` for the point (x, y) inside that cell. With
  /// require_known, a cell that is not known gives kUnknown. A distrusted cell (or, for a CCM
  /// layer, a distrusted cell pooled into it; for the constant layer, a distrusted neighbour of
  /// the roughness filter) gives kUnknown with upset set, whatever require_known. Precondition: the layer's window
  /// contains `index`; a violation (a bad layer included) is reported to the assert hook and
  /// answered kOutsideMap.
  [[nodiscard]] QueryResult answer_at(int layer, CellIndex index, float x, float y, bool require_known) const noexcept {
    CCMAP_ASSERT_OR_RETURN(layers_.contains(layer, index), empty_result(Status::kOutsideMap, -1));
    const float width = layers_.widths[layer];
    QueryResult out = empty_result(Status::kOk, layer);
    out.cell_width_m = width;
    if (Layers::is_ccm(layer)) {
      const typename Layers::CcmCellType cell = pooled(layers_, params_.weight_limit, layer, index);
      if (distrust_mark(cell)) {
        return upset_result(layer);  // integrity: a distrusted cell in the pool
      }
      if (!(cell.weight > 0.0F) && unobserved_drop(layer, index)) {
        return drop_answer(layer, index);  // nothing observed here or below, the rays proved a drop
      }
      const CcmSurface surface = ccm_surface(cell);
      // Known: covered (ccm_is_covered), or an obstacle already (classify_ccm: obstacle evidence wins).
      const CellClass cell_class = classify_ccm(cell, surface, width, params_, thresholds_[layer]);
      if (require_known && cell_class == CellClass::kUnknown) {
        return empty_result(Status::kUnknown, layer);
      }
      const float qx = x - grid::cell_centre(index.x, width);
      const float qy = y - grid::cell_centre(index.y, width);
      out.weight = cell.weight;
      out.height_m = ccm_height_at(cell, surface, qx, qy);
      out.slope_x = surface.slope_x;
      out.slope_y = surface.slope_y;
      out.inclination = ccm_inclination(surface);
      out.normal_variance = surface.normal_variance;
      out.elevation_variance = ccm_elevation_variance(cell, surface, qx, qy);
      out.cell_class = cell_class;
      return out;
    }
    if constexpr (Layers::kHasFine) {
      // Integrity: a distrusted cell answers unknown, upset (map/detail/integrity.hpp), never as
      // a drop-off either (what its records say cannot be trusted beside it).
      const FineCell& cell = layers_.fine.cell_unchecked(index);
      if (cell_distrusted(layers_, cell)) {
        return upset_result(layer);
      }
      if (!(cell.weight > 0.0F) && unobserved_drop(layer, index)) {
        return drop_answer(layer, index);
      }
      const bool known = cell.weight >= params_.min_weight && cell.weight > 0.0F;
      if (require_known && !known) {
        return empty_result(Status::kUnknown, layer);
      }
      out.weight = cell.weight;
      out.height_m = cell.height;
      out.normal_variance = fine_variance(cell);
      out.elevation_variance = out.normal_variance;
      out.cell_class = CellClass::kUnknown;
      if (known) {
        out.cell_class = roughness_class(index);
        if (out.cell_class == CellClass::kUnknown) {
          return upset_result(layer);  // a distrusted neighbour: the filter cannot judge the cell
        }
      }
    }
    return out;
  }

  /// What a known answer of a CCM layer takes from its (pooled) cell, whatever the point: the
  /// class (classify_ccm with the layer's threshold, as answer_at) and, only when the class is
  /// known, the surface (eqs. 9, 11; zero otherwise).
  struct CcmAnswer {
    CcmSurface surface;
    CellClass cell_class;
  };
  [[nodiscard]] CcmAnswer ccm_answer(int layer, const typename Layers::CcmCellType& cell) const noexcept {
    const CcmSurface surface = ccm_surface(cell);
    CcmAnswer a{CcmSurface{0.0F, 0.0F, 0.0F},
                classify_ccm(cell, surface, layers_.widths[layer], params_, thresholds_[layer])};
    if (a.cell_class != CellClass::kUnknown) {
      a.surface = surface;
    }
    return a;
  }

  /// A piece-wise constant cell (of the layers' storage, not distrusted: map/detail/integrity.hpp)
  /// is known with at least min_weight (and some weight).
  [[nodiscard]] bool fine_known(const FineCell& cell) const noexcept {
    return cell.weight >= params_.min_weight && cell.weight > 0.0F;
  }

  [[nodiscard]] const Layers& layers() const noexcept { return layers_; }
  /// The free-space records the view reads (nullptr without free space).
  [[nodiscard]] const DropRecords* drops() const noexcept { return drops_; }
  [[nodiscard]] const StackParams& params() const noexcept { return params_; }
  /// Normal-variance threshold of a layer (m^2). Precondition: 0 <= layer < kLayerCount; a
  /// violation is reported to the assert hook and answered 0 (every rough cell an obstacle).
  [[nodiscard]] float threshold(int layer) const noexcept {
    CCMAP_ASSERT_OR_RETURN(layer >= 0 && layer < Layers::kLayerCount, 0.0F);
    return thresholds_[layer];
  }

  /// Roughness filter of the piece-wise constant layer (the baseline of Section V-B): the
  /// cell is an obstacle if any known neighbour differs in height by more than the maximum
  /// inclination times their distance. It cannot tell slopes from steps. kUnknown if no step is
  /// found and a neighbour is distrusted (map/detail/integrity.hpp): it might have held one.
  [[nodiscard]] CellClass roughness_class(CellIndex index) const noexcept {
    if constexpr (Layers::kHasFine) {
      const FineCell& centre = layers_.fine.cell_unchecked(index);
      const float step = params_.max_inclination * layers_.widths[0];
      bool distrusted = false;
      for (std::int32_t dy = -1; dy <= 1; ++dy) {
        for (std::int32_t dx = -1; dx <= 1; ++dx) {
          const FineCell* n = layers_.fine.cell(CellIndex{index.x + dx, index.y + dy});
          if (n == nullptr || (dx == 0 && dy == 0)) {
            continue;
          }
          if (cell_distrusted(layers_, *n)) {
            distrusted = true;  // integrity: it cannot count as level ground
            continue;
          }
          if (!(n->weight >= params_.min_weight)) {
            continue;
          }
          const float limit = (dx != 0 && dy != 0) ? step * 1.41421356F : step;
          if (std::fabs(n->height - centre.height) > limit) {
            return CellClass::kObstacle;
          }
        }
      }
      return distrusted ? CellClass::kUnknown : CellClass::kTraversable;
    } else {
      (void)index;
      return CellClass::kUnknown;
    }
  }

 private:
  /// Replaces slope, normal variance and class of a constant-layer answer with those of the
  /// first CCM layer's pooled cell at (x, y), when that cell is known; with the upset answer
  /// when that cell is distrusted (hazards are a CCM matter: its class is lost).
  void refine_with_ccm(float x, float y, QueryResult& answer) const noexcept {
    const int layer = Layers::kFineLayerCount;
    CellIndex index{};
    if (!layers_.locate(layer, x, y, &index)) {
      return;
    }
    const QueryResult ccm = answer_at(layer, index, x, y, true);
    if (ccm.status != Status::kOk) {
      if (ccm.upset) {
        answer = upset_result(answer.layer);
      }
      return;
    }
    answer.slope_x = ccm.slope_x;
    answer.slope_y = ccm.slope_y;
    answer.inclination = ccm.inclination;
    answer.normal_variance = ccm.normal_variance;
    answer.cell_class = ccm.cell_class;
  }

  [[nodiscard]] float fine_weight(CellIndex index) const noexcept {
    if constexpr (Layers::kHasFine) {
      return layers_.fine.cell_unchecked(index).weight;
    } else {
      (void)index;
      return 0.0F;
    }
  }

  const Layers& layers_;
  const StackParams& params_;
  const float* thresholds_;
  const DropRecords* drops_;
};

}  // namespace ccmap::detail
