#pragma once
// Labelled PNG figures. Entry points:
//   Figure, spectrogram   panels, axes, lines, points and spectrograms (figure.hpp)
//   write_sound_png       the spectrogram every sound-making command writes (sound_figure.hpp)
#include "chladni/plot/figure.hpp"
#include "chladni/plot/sound_figure.hpp"
