#pragma once
// Material and damping from a recording of a real strike (Sterling & Lin 2016). Entry points:
//   read_recording     the strike, mono, checked and cut (recording.hpp)
//   extract_features   its decaying partials (features.hpp)
//   fit_damping        the damping curve through them (damping_fit.hpp)
//   fit_material       the material whose modes sound like it (material_fit.hpp)
#include "chladni/estimate/damping_fit.hpp"
#include "chladni/estimate/features.hpp"
#include "chladni/estimate/material_fit.hpp"
#include "chladni/estimate/recording.hpp"
