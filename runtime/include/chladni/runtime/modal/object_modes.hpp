#pragma once
// A sounding object's modes as voices see them, and how an impact excites them (DESIGN.md:
// q_i = (v_i(x) . n) J / omega_d for a model with geometry).
#include <complex>
#include <vector>

#include "chladni/core/modal_model.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/runtime/modal/synth.hpp"

namespace chladni::runtime {

/// What a scene object sounds like: its modes, and how an impact excites them.
struct ObjectModes {
  std::vector<ModeSpec> modes;  ///< damped angular frequency, decay, gain at 1 m
  /// Complex state kick per mode for an impact; filled by impact_coupling().
  const ModalModel* model = nullptr;  ///< geometry-backed objects
  const std::vector<InlineMode>* inline_modes = nullptr;
  /// Per-mode transfer (the model's, when it has one): gains then come from it, not from `gain`.
  const Transfer* transfer = nullptr;
};

/// Surface points an impact or a contact may name (0 without geometry).
inline std::size_t surface_points(const ObjectModes& o) {
  return o.model && o.model->has_geometry() ? o.model->points.size() : 0;
}

/// Builds the voice description of a modal model: gain_i = radiation_i * omega_d^2 (pressure from
/// modal acceleration at 1 m).
ObjectModes object_modes(const ModalModel& model);
/// Inline modes: amplitude is the pressure at 1 m per N*s of impulse.
ObjectModes object_modes(const std::vector<InlineMode>& modes);

/// Per-mode state kick of an impact's whole impulse (Synth::strike() spreads it over the
/// contact time).
void impact_coupling(const ObjectModes& object, const ImpactEvent& event,
                     std::vector<std::complex<float>>& out);

}  // namespace chladni::runtime
