#include "band_modes.hpp"

#include <cmath>
#include <numbers>

#include "surface/local_thickness.hpp"
#include "surface/split_long_edges.hpp"

namespace chladni::precompute {

// Three counts, added: Weyl's law for the elastic solid, N = V w^3 / (6 pi^2) (1/c_p^3 + 2/c_s^3);
// the in-plane waves of a membrane of the mid-surface (area S/2), N = (S/2) w^2 / (4 pi)
// (1/c_L^2 + 1/c_s^2) with c_L^2 = E / (rho (1 - nu^2)), which on a thick body stands in for the
// positive surface term Weyl's law lacks at low counts; and the bending waves of a Kirchhoff
// plate of the local thickness t, N = w / (4 pi) sqrt(12 rho (1 - nu^2) / E) * sum (A_i / 2) / t_i
// over the surface triangles (modal density S sqrt(rho h / D) / (4 pi); Cremer, Heckl &
// Petersson, Structure-Borne Sound, ch. 7). Solved counts at 20 kHz in steel against this
// estimate: bowl 72 (73), bell 90 (88), the rotor's ring 833 (793), a sphere 27 (23); a beam's
// (the bar: 21 against 9) is the one shape it undercounts by half.
double band_modes(const SurfaceMesh& input, const MeshReport& checked, const Material& m,
                  double max_frequency) {
  const double volume = std::abs(checked.volume);
  const double pi = std::numbers::pi;
  const double w = 2 * pi * max_frequency;
  const double cs = m.shear_speed();
  const double cp = cs * std::sqrt((m.lame_lambda() + 2 * m.lame_mu()) / m.lame_mu());
  const double solid =
      volume * w * w * w / (6 * pi * pi) * (1 / (cp * cp * cp) + 2 / (cs * cs * cs));
  // Rays leave from each triangle's centroid: a CAD face as two triangles over a thick and a thin
  // part would count as one or the other. Split, each piece is at most a twentieth of the size.
  const double diagonal = norm(sub(checked.bbox_max, checked.bbox_min));
  if (!(diagonal > 0) || !std::isfinite(diagonal)) return solid;
  const SurfaceMesh surface = split_long_edges(input, diagonal / 20);
  std::vector<double> area(surface.triangles.size());
  double total = 0;
  for (std::size_t i = 0; i < area.size(); ++i) {
    const auto& t = surface.triangles[i];
    const auto& v = surface.vertices;
    area[i] = 0.5 * norm(triangle_normal(v[t[0]], v[t[1]], v[t[2]]));
    total += area[i];
  }
  if (!(total > 0)) return solid;
  const std::vector<double> thickness = local_thickness(surface);
  const double mean = 2 * volume / total;  // where no ray came back
  double area_over_t = 0;
  for (std::size_t i = 0; i < area.size(); ++i)
    area_over_t += 0.5 * area[i] / (thickness[i] > 0 ? thickness[i] : mean);
  const double c_plate2 = m.youngs_modulus / (m.density * (1 - m.poisson_ratio * m.poisson_ratio));
  const double membrane = 0.5 * total * w * w / (4 * pi) * (1 / c_plate2 + 1 / (cs * cs));
  const double bending = w / (4 * pi) * std::sqrt(12 / c_plate2) * area_over_t;
  return solid + membrane + bending;
}

}  // namespace chladni::precompute
