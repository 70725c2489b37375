// Shared by the wave_*.comp kernels: the grid and the split-field coefficients.
// coef holds per axis a: pa[n_a], pb[n_a], wa[n_a], wb[n_a], axis after axis.
layout(push_constant) uniform Push {
  uvec4 n;       // cells along x, y, z; cells in all
  uvec4 pml_lo;  // cells in [pml_lo, pml_hi) on every axis have no split fields
  uvec4 pml_hi;
  uvec4 extra;   // per kernel: counts, step, sample slot
  float lambda;  // c dt / h
  uint groups_x; // invocations along y are rows of groups_x * local size
} pc;

uint invocation() {
  return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * pc.groups_x * gl_WorkGroupSize.x;
}

uint coef_base(uint axis) {
  return axis == 0u ? 0u : axis == 1u ? 4u * pc.n.x : 4u * (pc.n.x + pc.n.y);
}
