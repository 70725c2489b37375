#pragma once
// chladni estimate --plot: the recorded and resynthesized spectrograms and the damping ratio of
// the partials with the fitted curves, in one labelled PNG.
#include <string>
#include <vector>

#include "chladni/core/damping.hpp"
#include "chladni/estimate/features.hpp"
#include "chladni/estimate/recording.hpp"

namespace chladni::cli {

struct EstimatePlot {
  std::string path, title;
  const estimate::Recording* recording = nullptr;
  const estimate::FeatureSet* features = nullptr;   ///< of `recording`
  std::vector<double> resynthesized;                ///< from the strike on, same rate
  std::vector<const estimate::FeatureSet*> pooled;  ///< every recording's partials
  DampingModel curve;                               ///< through the partials
  const DampingModel* material = nullptr;           ///< the fitted material's, when there is one
};

void write_estimate_plot(const EstimatePlot& p);

}  // namespace chladni::cli
