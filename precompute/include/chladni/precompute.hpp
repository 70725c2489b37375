#pragma once
// From a closed triangle mesh to a soundbank. Entry points:
//   precompute_mesh, PrecomputeOptions   the whole pipeline for one asset, refined until its
//                                        estimate is within the tolerance (precompute.hpp)
//   read_mesh, check_mesh, repair_mesh   the surface, its checks and the repair ladder
//   acoustic transfer                    per-mode radiation (acoustic_transfer.hpp)
// Many assets, one process each and across MPI ranks: chladni/precompute/batch.hpp (the
// chladni_batch library).
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/mesh_repair.hpp"
#include "chladni/precompute/precompute.hpp"
#include "chladni/precompute/precompute_options.hpp"
#include "chladni/precompute/surface_mesh.hpp"
