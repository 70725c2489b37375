/* The smallest engine: a runtime, a struck object, one second of audio. Built by the tests;
 * run it with a soundbank path (chladni precompute ... -o bowl.chbank) or without (two inline
 * modes). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "chladni/chladni.h"

static int check(chladni_status s, const char* what) {
  if (s != CHLADNI_OK) fprintf(stderr, "%s: %s\n", what, chladni_last_error());
  return s != CHLADNI_OK;
}

int main(int argc, char** argv) {
  chladni_config config;
  chladni_config_default(&config); /* CPU, 48 kHz, stereo, blocks of 256 */
  chladni_runtime* rt = NULL;
  if (check(chladni_runtime_create(&config, &rt), "create")) return 1;

  chladni_bank bank = {0};
  if (argc > 1) {
    if (check(chladni_bank_load_file(rt, argv[1], &bank), "load")) return 1;
  } else {
    const double hz[2] = {441.0, 1142.0}, decay[2] = {2.0, 3.5}, pa[2] = {0.02, 0.01};
    if (check(chladni_bank_from_modes(rt, hz, decay, pa, 2, &bank), "modes")) return 1;
  }
  const double position[3] = {0.3, 1.0, 0.0}, identity[4] = {1, 0, 0, 0};
  chladni_object bowl = {0};
  if (check(chladni_object_spawn(rt, bank, position, identity, 1.0, &bowl), "spawn")) return 1;

  /* Game thread: strike it 10 ms from now with a 0.8 ms contact. */
  chladni_impact hit = {0};
  hit.object = bowl;
  hit.time = chladni_runtime_time(rt) + 0.01;
  hit.impulse = 0.01;
  hit.direction[0] = -1.0;
  hit.vertex = -1; /* the surface point nearest hit.point */
  hit.contact_time = 0.0008;
  if (check(chladni_impact_post(rt, &hit), "impact")) return 1;

  /* Audio thread: one second in the engine's buffer size. */
  float buffer[480 * 2];
  double peak = 0.0;
  for (int b = 0; b < 100; ++b) {
    if (check(chladni_runtime_render(rt, buffer, 480), "render")) return 1;
    for (int n = 0; n < 480 * 2; ++n) peak = fmax(peak, fabs(buffer[n]));
  }
  printf("%s: 1 s rendered, peak %.3g Pa\n", chladni_runtime_backend(rt), peak);

  /* Control thread, while the audio may still play: the bowl fades out over the gain ramp and
   * its bank is freed once it has. */
  if (check(chladni_object_remove(rt, bowl), "remove")) return 1;
  if (check(chladni_bank_release(rt, bank), "release")) return 1;
  double tail = 0.0;
  for (int b = 0; b < 2; ++b) {
    if (check(chladni_runtime_render(rt, buffer, 480), "render")) return 1;
    for (int n = 0; n < 480 * 2; ++n) tail = b == 1 ? fmax(tail, fabs(buffer[n])) : tail;
  }
  chladni_runtime_destroy(rt);
  return peak > 0.0 && tail == 0.0 ? 0 : 1;
}
