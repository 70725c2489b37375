#pragma once
// Chladni's value types and formats, shared by every other library. Entry points:
//   read_soundbank / write_soundbank   a precomputed object's modes and transfer (soundbank.hpp)
//   ModalModel, DampingModel           modes, damping models and band limits (modal_model.hpp,
//                                      damping.hpp)
//   find_material, material_presets   materials and their sources (material.hpp)
//   load_scene / parse_scene           scenes: objects, impacts, moves, shakes (scene.hpp)
//   read_audio / write_wav             audio files (audio_file.hpp)
//   analytic_bar                       a free bar's analytic modes (analytic_bar.hpp)
//   InputError, InternalError          what every call throws (error.hpp)
#include "chladni/core/analytic_bar.hpp"
#include "chladni/core/audio_file.hpp"
#include "chladni/core/damping.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/material.hpp"
#include "chladni/core/modal_model.hpp"
#include "chladni/core/paper_animation.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/core/soundbank.hpp"
