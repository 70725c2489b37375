#pragma once
// An object's modes as a recording would hear them: struck at one surface point and heard at a
// listener, by the runtime's impact and gain rules.
#include <cstddef>

#include "chladni/core/modal_model.hpp"
#include "chladni/core/vec3.hpp"
#include "chladni/estimate/material_fit.hpp"

namespace chladni::estimate {

/// Mode i's amplitude is |g_i (v_i(p) . n(p)) / omega_i| per N*s: an impulse along the surface
/// normal at point p (DESIGN.md's impact rule) times the gain g_i at `listener` per unit modal
/// acceleration (the transfer when the model has one). `gamma` is the model material's E / rho.
/// Throws InputError when the model has no geometry or `point` is out of range.
StruckModes struck_modes(const ModalModel& model, std::size_t point, const Vec3& listener,
                         double gamma);

}  // namespace chladni::estimate
