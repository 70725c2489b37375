#pragma once
// The synthesis engine. Entry points, from a whole scene down to one filterbank:
//   prepare_scene, render_scene, SceneTimeline   a scene file to sound, offline or block by block
//                                                (scene/prepare_scene.hpp, scene_timeline.hpp)
//   ScenePlayer                                  objects, a listener, impacts and shakers, live
//   resolve_objects, playable_model              soundbanks, bars and inline modes made playable
//   Synth                                        voices of modes over a filterbank (modal/)
//   ShakerBank, phisem_preset                    PhISEM particle voices (phisem/)
//   render_paper                                 paper sound from an animation (paper/)
//   make_filterbank                              the CPU or GPU filterbank (filterbank/)
// The C API over this library is chladni.h.
#include "chladni/runtime/filterbank/make_filterbank.hpp"
#include "chladni/runtime/modal/synth.hpp"
#include "chladni/runtime/paper/paper_synth.hpp"
#include "chladni/runtime/phisem/shaker_bank.hpp"
#include "chladni/runtime/scene/prepare_scene.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "chladni/runtime/scene/scene_player.hpp"
#include "chladni/runtime/scene/scene_timeline.hpp"
