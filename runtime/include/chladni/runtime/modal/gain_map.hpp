#pragma once
// Far-field acoustic transfer maps (FFAT maps: Chadwick, An & James, "Harmonic shells", 2009;
// Wang & James, "KleinPAT", 2019) for listener gains. A mode's expansion (core/transfer.hpp) is a
// polynomial in s = 1/r once the common phase is taken out (Atkinson-Wilcox):
//   r e^(-ikr) p(r, x^) = sum_(n <= L) F_n(x^) s^n.
// Beyond a valid radius r_v a quadratic in s is enough: the one through s = 0 (the exact far
// field), 1/r_v and 1/(sqrt2 r_v). Its complex coefficients C0, C1, C2 are sampled on an
// equiangular (theta, phi) grid; the complex pattern is as smooth as the expansion (band limit
// L), with none of the kinks |p| has at its nulls, so bilinear interpolation holds there too.
// A listener update then reads four grid nodes per mode (in half precision) instead of all
// (L+1)^2 coefficients.
// Per mode, r_v is the smallest radius of a ladder (R, sqrt2 R, 2R, ...) and the grid the
// coarsest of three sizes from 2L nodes over pi on (8 at least; sizes step by about 1.4) for
// which the model matches the expansion at check
// directions off the grid at every ladder radius beyond r_v and at infinity. Nearer listeners,
// and modes with no such radius, use the expansion itself (TransferTable).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "chladni/core/transfer.hpp"

namespace chladni::runtime {

class ThreadPool;

struct GainMapOptions {
  /// A model value v may differ from the expansion's |p| by tolerance |p| + floor max|p|, max
  /// over the check directions at that radius: 0.06 is 0.5 dB away from the pattern's nulls.
  double tolerance = 0.06;
  double floor = 0.01;
  /// No model is tried beyond this radius (in units of R): such modes use the expansion.
  double max_radius = 64.0;
  /// Directions (Fibonacci sphere) at which each model is checked against the expansion.
  int check_directions = 600;
};

/// A listener direction as fractions of the grid's extent: theta / pi and phi / (2 pi).
struct MapDirection {
  double theta = 0, phi = 0;
};
MapDirection map_direction(const Vec3& d);

/// Where a direction falls on a grid: the four surrounding nodes and bilinear weights.
struct GridCell {
  uint32_t node[4] = {0, 0, 0, 0};
  float weight[4] = {0, 0, 0, 0};
};
/// The cell of a grid of `rows` theta nodes (poles included) and `cols` periodic phi nodes.
GridCell grid_cell(uint32_t rows, uint32_t cols, const MapDirection& d);

struct GainMap {
  /// The modes that share one grid size, interleaved so that one node's values for all of them
  /// are contiguous.
  struct Grid {
    uint32_t rows = 0;  ///< theta nodes, poles included (theta_j = j pi / (rows - 1))
    uint32_t cols = 0;  ///< phi nodes, periodic (phi_c = c 2 pi / cols, phi = atan2(y, x))
    std::vector<uint32_t> modes;  ///< mode indices in the transfer
    uint32_t stride = 0;          ///< slots per node and component: modes.size()
    /// [(node 6 + c) stride + slot], c = Re, Im of C0, C1 r_v, C2 r_v^2, each over the
    /// mode's scale (so every value is at most 1), as IEEE half-precision bits.
    std::vector<uint16_t> coef;
    std::vector<float> scale, valid;  ///< per slot: the scale and r_v
    GridCell cell(const MapDirection& d) const;
  };
  std::vector<Grid> grids;
  uint32_t modes = 0;
  /// Per mode (m, object frame); +infinity where only the expansion is accurate enough.
  std::vector<float> valid_radius;
  std::vector<uint32_t> order;  ///< per mode: L
  float max_valid_radius = 0;   ///< over the modes with a finite radius
  uint32_t series_modes = 0;    ///< modes with no valid radius
  /// Valid radii in ascending order, and the highest order among the modes from there on.
  std::vector<float> step_radius;
  std::vector<int> step_order;

  /// The highest order among the modes whose valid radius exceeds r: the harmonics a listener
  /// at r needs. -1 when every mode has its map there.
  int series_order(float r) const;
  std::size_t bytes() const;
};

/// Builds the maps of all modes of `t` (threads from `pool` when given).
GainMap build_gain_map(const Transfer& t, const GainMapOptions& options = {},
                       ThreadPool* pool = nullptr);

/// The model |p| at distance 1 / s for every mode of a grid, into out[mode index]. Vectorizes
/// over the grid's modes.
void grid_gains(const GainMap::Grid& g, const GridCell& cell, float s, float* out);

}  // namespace chladni::runtime
