#include "chladni/runtime/paper/paper_spatial.hpp"

#include <algorithm>
#include <cmath>

namespace chladni::runtime {

std::array<Vec3, 2> ear_positions(const PaperListener& l) {
  Vec3 right = cross(l.forward, l.up);
  const double n = norm(right);
  right = n > 1e-12 ? scale(right, 1 / n) : Vec3{1, 0, 0};
  return {add(l.position, scale(right, -0.5 * l.ear_distance)),
          add(l.position, scale(right, 0.5 * l.ear_distance))};
}

namespace {

SoundPath path(const Vec3& y, const Vec3& n, double size, const Vec3& x,
               const PaperSpatialOptions& o) {
  const Vec3 d = sub(x, y);  // Eq. 2: R = x - y
  const double r = norm(d);
  const double cos_theta = r > 0 ? dot(d, n) / r : 0;
  return {size * cos_theta / std::max(r, o.min_distance), r / o.sound_speed};
}

}  // namespace

void dipole_paths(const Vec3& center, const Vec3& normal, double a, double reference_radius,
                  const Vec3& ear, std::span<const PaperObstacle> obstacles,
                  const PaperSpatialOptions& o, std::vector<SoundPath>& out) {
  const double size = std::pow(a / reference_radius, 3);
  out.push_back(path(center, normal, size, ear, o));
  for (const PaperObstacle& p : obstacles) {
    const double h = dot(sub(center, p.point), p.normal);  // source height above the plane
    const double e = dot(sub(ear, p.point), p.normal);
    // The image exists for a source and a listener on the open side of the plane.
    if (h < 0 || e <= 0 || h > o.max_image_distance) continue;
    // Mirror position and normal: the rigid plane's dp/dn = 0 (Eq. 4).
    const Vec3 y = sub(center, scale(p.normal, 2 * h));
    const Vec3 n = sub(normal, scale(p.normal, 2 * dot(normal, p.normal)));
    // A disk lying on the plane would cancel against its image (a vertical dipole on a
    // rigid floor), yet a sheet flat on a table sounds: its top face radiates into the half
    // space. Below one disk radius the image fades out (weight h / a), leaving the direct lobe.
    SoundPath image = path(y, n, size, ear, o);
    image.gain *= std::min(1.0, h / a);
    out.push_back(image);
  }
}

double path_magnitude(std::span<const SoundPath> paths, double omega) {
  std::complex<double> s = 0;
  for (const SoundPath& p : paths) s += p.gain * std::polar(1.0, omega * p.delay);
  return std::abs(s);
}

}  // namespace chladni::runtime
