#include "chladni/runtime/modal/gain_map.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstring>
#include <limits>
#include <numbers>
#include <numeric>

#include "chladni/core/spherical.hpp"
#include "chladni/runtime/thread_pool.hpp"

namespace chladni::runtime {
namespace {

using cd = std::complex<double>;

// Grid sizes (nodes over pi) a mode may get: few distinct sizes keep the cells a listener
// update computes per object few.
constexpr uint32_t kSizes[] = {4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256, 384, 512};

uint32_t grid_size(uint32_t nodes) {
  for (uint32_t n : kSizes)
    if (n >= nodes) return n;
  return 0;  // finer than any grid: the expansion is used
}

uint32_t next_size(uint32_t n) {
  for (uint32_t m : kSizes)
    if (m > n) return m;
  return 0;
}

// One grid size's tables: Legendre rows Y_lm(theta_j, phi = 0) and cos/sin(m phi_c) columns.
struct Tables {
  uint32_t n = 0, rows = 0, cols = 0;
  std::vector<double> rows_sh, cos_t, sin_t;
  std::vector<GridCell> check_cell;
};

struct Shared {
  const Transfer* t = nullptr;
  const GainMapOptions* o = nullptr;
  int top = 0;
  std::vector<Tables> tables;  // one per kSizes entry used
  std::vector<MapDirection> check;
  std::vector<double> check_sh;  // per check direction: Y_lm, all m
  std::vector<double> ladder;    // candidate radii (m)
  const Tables* find(uint32_t n) const {
    for (const Tables& tb : tables)
      if (tb.n == n) return &tb;
    return nullptr;
  }
};

// What one mode's build yields.
struct ModeMap {
  uint32_t n = 0;  // 0: no map
  float valid = std::numeric_limits<float>::infinity();
  float scale = 0;
  std::vector<uint16_t> values;  // [node 6 + c], normalized as GainMap::Grid::coef
};

// C0, C1 r_v, C2 r_v^2 over their largest component, rounded to half precision; the model
// is checked with the rounded values.
uint16_t to_half(double x) {
  const _Float16 f = static_cast<_Float16>(x);
  uint16_t h;
  std::memcpy(&h, &f, sizeof h);
  return h;
}

double from_half(uint16_t h) {
  _Float16 f;
  std::memcpy(&f, &h, sizeof f);
  return static_cast<double>(f);
}

float normalize(const std::vector<std::array<cd, 3>>& c, double rv, std::vector<uint16_t>& out) {
  double top = 0;
  for (const auto& n : c)
    for (int q = 0; q < 3; ++q) {
      const cd x = n[q] / std::pow(rv, q);
      top = std::max({top, std::abs(x.real()), std::abs(x.imag())});
    }
  const double scale = top > 0 ? top : 1.0;
  out.resize(c.size() * 6);
  for (std::size_t node = 0; node < c.size(); ++node)
    for (int q = 0; q < 3; ++q) {
      const cd x = c[node][q] / (std::pow(rv, q) * scale);
      out[node * 6 + 2 * q] = to_half(x.real());
      out[node * 6 + 2 * q + 1] = to_half(x.imag());
    }
  return static_cast<float>(scale);
}

// The pattern sum_l w_l sum_m a_lm Y_lm on a whole grid. Row by row: B_m = sum_l w_l a_lm
// Y_l|m|(theta, 0), then the phi sum over cos(m phi), sin(m phi).
void eval_grid(const Tables& tb, int top, const std::complex<float>* a, int L, const cd* w,
               std::vector<cd>& out) {
  const std::size_t shc = sh_count(top);
  std::vector<cd> b(2 * L + 1);
  std::vector<double> re(tb.cols), im(tb.cols);
  out.resize(std::size_t(tb.rows) * tb.cols);
  for (uint32_t j = 0; j < tb.rows; ++j) {
    const double* y = tb.rows_sh.data() + j * shc;
    for (int m = -L; m <= L; ++m) {
      cd acc = 0;
      const int am = std::abs(m);
      for (int l = am; l <= L; ++l) acc += w[l] * cd(a[sh_index(l, m)]) * y[sh_index(l, am)];
      b[m + L] = acc;
    }
    std::fill(re.begin(), re.end(), b[L].real());
    std::fill(im.begin(), im.end(), b[L].imag());
    for (int m = 1; m <= L; ++m) {
      const double* c = tb.cos_t.data() + std::size_t(m) * tb.cols;
      const double* sn = tb.sin_t.data() + std::size_t(m) * tb.cols;
      const double cr = b[L + m].real(), ci = b[L + m].imag();
      const double sr = b[L - m].real(), si = b[L - m].imag();
      for (uint32_t col = 0; col < tb.cols; ++col) {
        re[col] += cr * c[col] + sr * sn[col];
        im[col] += ci * c[col] + si * sn[col];
      }
    }
    for (uint32_t col = 0; col < tb.cols; ++col) out[j * tb.cols + col] = cd(re[col], im[col]);
  }
}

// Per-order weights that turn the patterns S_l into r e^(-ikr) p at radius r; at infinity
// h_l(kr) -> (-i)^(l+1) e^(ikr) / (kr), so the limit is sum_l (-i)^(l+1) / (k h_l(kR)) S_l.
std::vector<cd> radius_weights(int L, double k, double radius, double r) {
  std::vector<cd> w(L + 1, 0.0);
  if (std::isinf(r)) {
    std::vector<cd> h(L + 1);
    sph_hankel1(L, k * radius, h.data());
    const cd minus_i(0, -1);
    cd phase = minus_i;
    for (int l = 0; l <= L; ++l, phase *= minus_i) {
      if (!std::isfinite(h[l].real()) || !std::isfinite(h[l].imag()) || h[l] == 0.0) break;
      w[l] = phase / (k * h[l]);
    }
  } else {
    sph_hankel1_ratio(L, k * r, k * radius, w.data());
    const cd f = r * std::exp(cd(0, -k * r));
    for (cd& x : w) x *= f;
  }
  return w;
}

// The quadratic in s through (0, g0), (s1, g1), (s2, g2), as monomial coefficients.
std::array<cd, 3> quadratic(cd g0, cd g1, cd g2, double s1, double s2) {
  const cd d1 = g1 - g0, d2 = g2 - g0;
  const double det = s1 * s2 * (s2 - s1);
  return {g0, (d1 * s2 * s2 - d2 * s1 * s1) / det, (d2 * s1 - d1 * s2) / det};
}

bool within(const GainMapOptions& o, double v, double e, double peak) {
  return std::abs(v - e) <= o.tolerance * e + o.floor * peak;
}

// Does the grid model hold at the check directions at ladder radii from `first` on (and at
// infinity, the last row of `exact`, which holds r e^(-ikr) p)?
bool model_holds(const Shared& s, const Tables& tb, const std::vector<uint16_t>& v, double scale,
                 double rv, const std::vector<std::vector<cd>>& exact, std::size_t first) {
  for (std::size_t ri = first; ri < exact.size(); ++ri) {
    const double sr = ri + 1 == exact.size() ? 0.0 : rv / s.ladder[ri];
    double peak = 0;
    for (const cd& x : exact[ri]) peak = std::max(peak, std::abs(x));
    for (std::size_t p = 0; p < s.check.size(); ++p) {
      const GridCell& c = tb.check_cell[p];
      cd acc = 0;
      for (int n = 0; n < 4; ++n) {
        const uint16_t* f = v.data() + std::size_t(c.node[n]) * 6;
        auto at = [&](int q) { return cd(from_half(f[2 * q]), from_half(f[2 * q + 1])); };
        acc += double(c.weight[n]) * (at(0) + sr * (at(1) + sr * at(2)));
      }
      if (!within(*s.o, scale * std::abs(acc), std::abs(exact[ri][p]), peak)) return false;
    }
  }
  return true;
}

ModeMap build_mode(const Shared& s, uint32_t i) {
  const Transfer& t = *s.t;
  const ModeTransfer& mt = t.modes[i];
  const int L = static_cast<int>(mt.order);
  const std::complex<float>* a = t.coefficients_of(i);
  const double k = mt.wavenumber;
  ModeMap out;
  if (!(k > 0)) return out;

  // The expansion at the check directions: per order S_l, then r e^(-ikr) p at each ladder
  // radius and at infinity (last).
  const std::size_t np = s.check.size(), shc = sh_count(s.top);
  std::vector<cd> S(np * (L + 1), 0.0);
  for (std::size_t p = 0; p < np; ++p)
    for (int l = 0; l <= L; ++l)
      for (int m = -l; m <= l; ++m)
        S[p * (L + 1) + l] += cd(a[sh_index(l, m)]) * s.check_sh[p * shc + sh_index(l, m)];
  const std::vector<double>& radii = s.ladder;
  std::vector<std::vector<cd>> w(radii.size() + 1), exact(radii.size() + 1);
  for (std::size_t r = 0; r <= radii.size(); ++r) {
    w[r] = radius_weights(L, k, t.radius,
                          r < radii.size() ? radii[r] : std::numeric_limits<double>::infinity());
    exact[r].assign(np, 0.0);
    for (std::size_t p = 0; p < np; ++p)
      for (int l = 0; l <= L; ++l) exact[r][p] += w[r][l] * S[p * (L + 1) + l];
  }
  // Radii whose quadratic holds further out with the exact pattern (no grid yet).
  std::vector<std::size_t> candidates;
  for (std::size_t r = 0; r + 1 < radii.size(); ++r) {
    const double s1 = 1 / radii[r], s2 = 1 / radii[r + 1];
    bool ok = true;
    for (std::size_t r2 = r + 2; r2 < radii.size() && ok; ++r2) {
      const double sr = 1 / radii[r2];
      double peak = 0;
      for (const cd& x : exact[r2]) peak = std::max(peak, std::abs(x));
      for (std::size_t p = 0; p < np && ok; ++p) {
        const auto c = quadratic(exact.back()[p], exact[r][p], exact[r + 1][p], s1, s2);
        ok = within(*s.o, std::abs(c[0] + sr * (c[1] + sr * c[2])), std::abs(exact[r2][p]), peak);
      }
    }
    if (ok) candidates.push_back(r);
  }
  if (candidates.empty()) return out;

  std::vector<cd> g0, g1, g2;
  std::vector<std::array<cd, 3>> c;
  std::vector<uint16_t> v;
  // From 2L nodes over pi up through the next two sizes.
  const uint32_t first = grid_size(std::max<uint32_t>(8, 2 * uint32_t(L)));
  for (uint32_t n = first, tries_left = 3; n != 0 && tries_left > 0;
       n = next_size(n), --tries_left) {
    const Tables* found = s.find(n);
    if (!found) break;
    const Tables& tb = *found;
    eval_grid(tb, s.top, a, L, w.back().data(), g0);
    c.assign(g0.size(), {0.0, 0.0, 0.0});
    for (std::size_t node = 0; node < g0.size(); ++node) c[node][0] = g0[node];
    double scale = normalize(c, 1.0, v);
    if (!model_holds(s, tb, v, scale, 1.0, exact, radii.size())) continue;  // far field misses
    for (std::size_t tries = 0; tries < std::min<std::size_t>(3, candidates.size()); ++tries) {
      const std::size_t r = candidates[tries];
      eval_grid(tb, s.top, a, L, w[r].data(), g1);
      eval_grid(tb, s.top, a, L, w[r + 1].data(), g2);
      for (std::size_t node = 0; node < g0.size(); ++node)
        c[node] = quadratic(g0[node], g1[node], g2[node], 1 / radii[r], 1 / radii[r + 1]);
      scale = normalize(c, radii[r], v);
      if (model_holds(s, tb, v, scale, radii[r], exact, r)) {
        out.n = n;
        out.valid = static_cast<float>(radii[r]);
        out.scale = static_cast<float>(scale);
        out.values = std::move(v);
        return out;
      }
    }
  }
  return out;
}

struct BuildContext {
  const Shared* shared;
  std::vector<ModeMap>* maps;
};

void build_task(void* ctx, int index) {
  auto& c = *static_cast<BuildContext*>(ctx);
  (*c.maps)[index] = build_mode(*c.shared, static_cast<uint32_t>(index));
}

Shared prepare(const Transfer& t, const GainMapOptions& o) {
  Shared s;
  s.t = &t;
  s.o = &o;
  for (const ModeTransfer& m : t.modes) s.top = std::max(s.top, int(m.order));
  const std::size_t shc = sh_count(s.top);
  const int np = std::max(8, o.check_directions);
  s.check_sh.resize(np * shc);
  for (int p = 0; p < np; ++p) {
    // Fibonacci sphere: nearly uniform and off the grids' nodes.
    const double z = 1.0 - (2.0 * p + 1.0) / np;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double ph = p * std::numbers::pi * (3.0 - std::sqrt(5.0));
    const Vec3 d{rho * std::cos(ph), rho * std::sin(ph), z};
    s.check.push_back(map_direction(d));
    real_sh(s.top, d, s.check_sh.data() + p * shc);
  }
  // Tables for every size a mode may try: up to two sizes past the one for 2L.
  // Orders too high for the largest grid stay with the series.
  const uint32_t largest = kSizes[std::size(kSizes) - 1];
  uint32_t finest = grid_size(std::clamp<uint32_t>(2 * uint32_t(s.top), 8, largest));
  for (int k = 0; k < 2 && next_size(finest) != 0; ++k) finest = next_size(finest);
  for (uint32_t n : kSizes) {
    if (n > finest) break;
    Tables tb;
    tb.n = n, tb.rows = n + 1, tb.cols = 2 * n;
    tb.rows_sh.resize(tb.rows * shc);
    for (uint32_t j = 0; j < tb.rows; ++j) {
      const double th = std::numbers::pi * j / double(n);
      real_sh(s.top, {std::sin(th), 0.0, std::cos(th)}, tb.rows_sh.data() + j * shc);
    }
    tb.cos_t.resize(std::size_t(s.top + 1) * tb.cols);
    tb.sin_t.resize(tb.cos_t.size());
    for (int m = 0; m <= s.top; ++m)
      for (uint32_t c = 0; c < tb.cols; ++c) {
        const double ph = 2 * std::numbers::pi * c / double(tb.cols);
        tb.cos_t[m * tb.cols + c] = std::cos(m * ph);
        tb.sin_t[m * tb.cols + c] = std::sin(m * ph);
      }
    for (const MapDirection& d : s.check) tb.check_cell.push_back(grid_cell(tb.rows, tb.cols, d));
    s.tables.push_back(std::move(tb));
  }
  for (double f = 1.0; f <= o.max_radius * (1 + 1e-9); f *= std::numbers::sqrt2)
    s.ladder.push_back(f * t.radius);
  return s;
}

// Groups the modes by grid size, interleaving each group's values node by node.
void assemble(const Shared& s, std::vector<ModeMap>& built, GainMap& map) {
  for (uint32_t n : kSizes) {
    GainMap::Grid g;
    for (uint32_t i = 0; i < map.modes; ++i)
      if (built[i].n == n) g.modes.push_back(i);
    if (g.modes.empty()) continue;
    g.rows = n + 1, g.cols = 2 * n;
    const std::size_t nodes = std::size_t(g.rows) * g.cols, cnt = g.modes.size();
    g.stride = static_cast<uint32_t>(cnt);
    g.coef.assign(nodes * 6 * cnt, 0);
    g.scale.assign(cnt, 0.0f);
    g.valid.assign(cnt, 0.0f);
    for (std::size_t slot = 0; slot < g.modes.size(); ++slot) {
      ModeMap& b = built[g.modes[slot]];
      g.scale[slot] = b.scale;
      g.valid[slot] = b.valid;
      for (std::size_t node = 0; node < nodes; ++node)
        for (int c = 0; c < 6; ++c) g.coef[(node * 6 + c) * cnt + slot] = b.values[node * 6 + c];
      std::vector<uint16_t>().swap(b.values);
    }
    map.grids.push_back(std::move(g));
  }
  (void)s;
}

}  // namespace

GainMap build_gain_map(const Transfer& t, const GainMapOptions& o, ThreadPool* pool) {
  t.validate();
  GainMap map;
  map.modes = static_cast<uint32_t>(t.mode_count());
  if (map.modes == 0) return map;
  const Shared s = prepare(t, o);
  std::vector<ModeMap> built(map.modes);
  BuildContext ctx{&s, &built};
  if (pool)
    pool->run(build_task, &ctx, static_cast<int>(map.modes));
  else
    for (uint32_t i = 0; i < map.modes; ++i) build_task(&ctx, int(i));

  for (uint32_t i = 0; i < map.modes; ++i) {
    map.valid_radius.push_back(built[i].valid);
    map.order.push_back(t.modes[i].order);
    if (std::isfinite(built[i].valid))
      map.max_valid_radius = std::max(map.max_valid_radius, built[i].valid);
    else
      ++map.series_modes;
  }
  // Series orders by radius: the highest order among modes whose valid radius is beyond each
  // step (suffix maxima over the ascending radii).
  std::vector<uint32_t> idx(map.modes);
  std::iota(idx.begin(), idx.end(), 0u);
  std::sort(idx.begin(), idx.end(),
            [&](uint32_t x, uint32_t y) { return map.valid_radius[x] < map.valid_radius[y]; });
  int run = -1;
  for (auto it = idx.rbegin(); it != idx.rend(); ++it) {
    run = std::max(run, int(map.order[*it]));
    map.step_radius.push_back(map.valid_radius[*it]);
    map.step_order.push_back(run);
  }
  std::reverse(map.step_radius.begin(), map.step_radius.end());
  std::reverse(map.step_order.begin(), map.step_order.end());
  assemble(s, built, map);
  return map;
}

}  // namespace chladni::runtime
