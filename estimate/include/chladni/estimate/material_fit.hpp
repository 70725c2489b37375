#pragma once
// The material that makes an object's modes sound like a recorded strike (Ren et al. 2013;
// Sterling & Lin 2016 Sec. 1.3): the specific modulus gamma = E / rho (frequencies scale with
// sqrt(gamma)), an amplitude scale, the strike's contact time (a mallet's softness: it decides
// how the partials' amplitudes fall with frequency) and the damping model's parameters, found by a
// derivative-free search (NLopt's BOBYQA) of the hybrid metric from several starting points;
// the damping curve is then refitted to the measured decays of the partials the modes explain.
#include <cstddef>
#include <span>
#include <vector>

#include "chladni/core/damping.hpp"
#include "chladni/estimate/damping_fit.hpp"
#include "chladni/estimate/features.hpp"
#include "chladni/estimate/metric.hpp"

namespace chladni::estimate {

/// An object's modes at a reference material, struck at one point: undamped angular frequency
/// and the pressure amplitude at the listener per N*s of impulse (the runtime's impact rule).
struct StruckModes {
  std::vector<double> omega;      ///< rad/s
  std::vector<double> amplitude;  ///< Pa per N*s
  double gamma = 0;               ///< E / rho of the reference material (m^2/s^2)
};

struct MaterialFitOptions {
  DampingModel shape{DampingModel::Kind::PowerLaw, {0, 0}};  ///< the kind and term count
  std::size_t starts = 4;         ///< local searches, from the best of the starting points
  std::size_t evaluations = 600;  ///< metric evaluations per local search
  double max_frequency = 0;       ///< Hz; the band compared (0: the recording's)
};

struct MaterialFit {
  double gamma = 0;            ///< E / rho (m^2/s^2)
  double frequency_scale = 0;  ///< sqrt(gamma / reference gamma)
  double amplitude_scale = 0;  ///< recorded amplitude per modelled Pa
  double contact_time = 0;     ///< s: the strike's half-sine force (runtime's impact model)
  /// The damping through the decays of the partials the fitted modes explain (the result).
  DampingModel damping;
  /// The damping where the metric search ended (before the decays refine it).
  DampingModel search_damping;
  std::size_t matched_partials = 0;        ///< partials within 1 % of a fitted mode
  double psycho = 0, mrp = 0, hybrid = 0;  ///< the metric at the result (Eq. 1.5, 1.8, 1.9)
  std::size_t evaluations = 0;
  std::size_t starts_tried = 0;
  std::vector<Partial> modes;  ///< the fitted object's partials within the band
};

/// Fits gamma, the amplitude scale and the damping to the recording's features and psychoacoustic
/// spectrogram. `damping_start` (the damping curve fitted to the features) seeds the damping.
/// Throws InputError when the modes or features are empty.
MaterialFit fit_material(const FeatureSet& features, const PsychoSpectrogram& target,
                         const StruckModes& modes, const DampingFit& damping_start,
                         const MaterialFitOptions& options);

/// The same from the recorded samples (`x[0]` the file's first sample, `features` extracted from
/// it): builds the psychoacoustic target from the strike on, with the features' residual as its
/// noise floor, and fits.
MaterialFit fit_material(std::span<const double> x, double sample_rate, const FeatureSet& features,
                         const StruckModes& modes, const DampingFit& damping_start,
                         const MaterialFitOptions& options);

/// The object's partials for given parameters, struck by a half-sine force of `contact_time`
/// (modes outside (20 Hz, max_frequency) or overdamped are left out).
std::vector<Partial> model_partials(const StruckModes& modes, double frequency_scale,
                                    double amplitude_scale, double contact_time,
                                    const DampingModel& damping, double max_frequency);

}  // namespace chladni::estimate
