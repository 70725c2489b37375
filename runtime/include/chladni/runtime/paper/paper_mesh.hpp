#pragma once
// The paper sheet as a surface: its fixed connectivity (edges, borders, a consistent
// orientation) and, per frame, the differential geometry the paper-sound analysis reads
// (Schreck et al. 2016, §4): dihedral angles, mean curvature, principal curvature and the
// ruling direction of each face.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "chladni/core/vec3.hpp"

namespace chladni::runtime {

struct PaperTopology {
  std::uint32_t vertex_count = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles;   ///< consistently oriented
  std::vector<std::array<std::uint32_t, 2>> edges;       ///< (a, b) as face edge_faces[0] walks it
  std::vector<std::array<std::int32_t, 2>> edge_faces;   ///< second is -1 on the sheet's border
  std::vector<std::array<std::uint32_t, 3>> face_edges;  ///< edge k joins corners k and k+1
  std::vector<std::uint32_t> vertex_edge_start, vertex_edges;  ///< CSR: edges at each vertex
  std::uint32_t flipped_faces = 0;  ///< faces re-oriented to agree with their neighbours

  /// Builds the connectivity; throws InputError on an edge shared by more than two faces or a
  /// non-orientable sheet, naming the edge.
  static PaperTopology build(std::uint32_t vertex_count,
                             std::vector<std::array<std::uint32_t, 3>> triangles);
  bool border(std::uint32_t edge) const { return edge_faces[edge][1] < 0; }
  std::span<const std::uint32_t> edges_at(std::uint32_t v) const {
    return {vertex_edges.data() + vertex_edge_start[v],
            vertex_edge_start[v + 1] - vertex_edge_start[v]};
  }
  std::uint32_t other(std::uint32_t edge, std::uint32_t v) const {
    return edges[edge][0] == v ? edges[edge][1] : edges[edge][0];
  }
};

/// Geometry of one frame. Buffers are reused across frames: nothing is allocated once sized.
/// `update` computes what every frame needs (event detection); `update_shape` the principal
/// curvatures and rulings, needed only on frames with events.
struct PaperGeometry {
  std::vector<Vec3> position;          ///< per vertex, m
  std::vector<Vec3> face_normal;       ///< unit
  std::vector<double> face_area;       ///< m^2
  std::vector<Vec3> vertex_normal;     ///< unit, area weighted
  std::vector<double> vertex_area;     ///< barycentric, m^2
  std::vector<double> dihedral;        ///< per edge, signed, rad (0 on borders)
  std::vector<double> edge_length;     ///< m
  std::vector<double> mean_curvature;  ///< per vertex, 1/m: sum(theta_e |e|) / (4 A_v)
  std::vector<double> face_curvature;  ///< per face, larger |principal curvature| (update_shape)
  std::vector<Vec3> ruling;  ///< per face, unit direction of the smaller one (update_shape)

  void update(const PaperTopology& topo, std::span<const float> xyz);
  void update_shape(const PaperTopology& topo);
};

}  // namespace chladni::runtime
