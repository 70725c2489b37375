#pragma once
// The solid's thickness under each surface triangle, for estimating how many modes a thin part
// holds before any mesh is made. Only local_thickness.cpp and mesh_check.cpp include CGAL.
#include <vector>

#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

/// Per triangle: the shape diameter function (Shapira, Shamir & Cohen-Or 2008, CGAL's
/// sdf_values), the robust mean length of rays cast inward in a narrow cone about the inward
/// normal: a wall's thickness, a solid's chord. 0 where no ray came back (through a hole of an
/// open surface); all 0 when the surface is not a polygon mesh (non-manifold).
std::vector<double> local_thickness(const SurfaceMesh& surface);

/// The thinnest wall (m): the thickness below which lies the thinnest twentieth of the measured
/// surface by area, so that a few faces where a ray slipped between neighbours do not decide;
/// 0 when nothing was measured.
double thinnest_wall(const SurfaceMesh& surface);

}  // namespace chladni::precompute
