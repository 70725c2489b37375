/* The C API from C: compiled as C11, so the header stays C. Exits non-zero on the first
 * failed check, naming it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chladni/chladni.h"

#define CHECK(cond)                                                                         \
  do {                                                                                      \
    if (!(cond)) {                                                                          \
      fprintf(stderr, "%s:%d: %s (%s)\n", __FILE__, __LINE__, #cond, chladni_last_error()); \
      return 1;                                                                             \
    }                                                                                       \
  } while (0)

int main(void) {
  chladni_config config;
  chladni_config_default(&config);
  config.threads = 1;
  chladni_runtime* rt = NULL;
  CHECK(chladni_runtime_create(&config, &rt) == CHLADNI_OK);
  CHECK(strstr(chladni_runtime_backend(rt), "cpu") != NULL);

  const double hz[2] = {440.0, 1320.0}, decay[2] = {3.0, 6.0}, amp[2] = {1.0, 0.5};
  chladni_bank bank = {0};
  CHECK(chladni_bank_from_modes(rt, hz, decay, amp, 2, &bank) == CHLADNI_OK);
  CHECK(chladni_bank_mode_count(rt, bank) == 2);
  const double at[3] = {1.0, 2.0, 0.0}, identity[4] = {1, 0, 0, 0};
  chladni_object object = {99};
  CHECK(chladni_object_spawn(rt, bank, at, identity, 1.0, &object) == CHLADNI_OK);
  CHECK(object.id != 0 && object.id != 99);

  chladni_impact hit;
  memset(&hit, 0, sizeof hit);
  hit.object = object;
  hit.time = 0.01;
  hit.impulse = 0.01;
  hit.direction[2] = -1.0;
  hit.vertex = -1;
  hit.contact_time = 0.0005;
  CHECK(chladni_impact_post(rt, &hit) == CHLADNI_OK);

  /* 0.5 s in blocks of 120: silence before the impact, a ringing 440 Hz after it. */
  float* out = calloc(24000 * 2, sizeof(float));
  for (int b = 0; b < 24000 / 120; ++b)
    CHECK(chladni_runtime_render(rt, out + b * 120 * 2, 120) == CHLADNI_OK);
  CHECK(fabs(chladni_runtime_time(rt) - 0.5) < 1e-12);
  double before = 0, after = 0;
  for (int n = 0; n < 24000 * 2; ++n) {
    CHECK(isfinite(out[n]));
    if (n < 480 * 2)
      before = fmax(before, fabs(out[n]));
    else
      after = fmax(after, fabs(out[n]));
  }
  CHECK(before == 0.0);
  CHECK(after > 1e-4);
  free(out);

  /* Bad input: a status, a message naming the problem, nothing queued. */
  hit.impulse = NAN;
  CHECK(chladni_impact_post(rt, &hit) == CHLADNI_INPUT_ERROR);
  CHECK(strstr(chladni_last_error(), "impulse") != NULL);
  hit.impulse = 0.01;
  hit.object.id = 7;
  CHECK(chladni_impact_post(rt, &hit) == CHLADNI_INPUT_ERROR);
  CHECK(strstr(chladni_last_error(), "no object 7") != NULL);
  /* Released banks are freed once their objects are gone; their handles are refused. */
  CHECK(chladni_bank_release(rt, bank) == CHLADNI_OK);
  CHECK(chladni_bank_mode_count(rt, bank) == 0);
  CHECK(chladni_object_spawn(rt, bank, at, identity, 1.0, &object) == CHLADNI_INPUT_ERROR);
  CHECK(strstr(chladni_last_error(), "released") != NULL);
  chladni_bank missing = {0};
  CHECK(chladni_bank_load_file(rt, "/nonexistent/bowl.chbank", &missing) == CHLADNI_INPUT_ERROR);
  CHECK(strstr(chladni_last_error(), "/nonexistent/bowl.chbank") != NULL);
  const double up[3] = {0, 0, 1};
  CHECK(chladni_listener_set(rt, 0.6, at, up, up) == CHLADNI_INPUT_ERROR);
  CHECK(strstr(chladni_last_error(), "parallel") != NULL);

  chladni_runtime_destroy(rt);
  puts("C API smoke test passed");
  return 0;
}
