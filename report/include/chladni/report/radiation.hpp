#pragma once
// How loudly each mode of an object radiates, by direction, with the runtime's listener-gain
// rule: the multipole expansion where the bank's transfer is usable, else the compact-source
// estimate. `chladni info --plot` and the report's directivity both draw from it.
#include <vector>

#include "chladni/core/modal_model.hpp"
#include "chladni/core/vec3.hpp"

namespace chladni::report {

/// |gain| of every mode at `distance` from `centre` along each of the unit `directions`:
/// result[direction][mode].
std::vector<std::vector<double>> gains_towards(const ModalModel& model, const Vec3& centre,
                                               double distance,
                                               const std::vector<Vec3>& directions);

/// Pressure at 1 m per unit modal acceleration (Pa s^2), rms over 14 directions (the six axes
/// and eight diagonals) at max(1 m, 4 R) from the transfer's centre, scaled back by distance and
/// omega_d^2; NaN for a mode with no damped frequency.
std::vector<double> radiation_at_1m(const ModalModel& model);

}  // namespace chladni::report
