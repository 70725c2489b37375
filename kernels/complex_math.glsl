// Complex helpers shared by the transfer kernels. cis(t) = (cos t, sin t) with its own range
// reduction and polynomials: Vulkan only promises 2^-11 absolute error for the built-in sin/cos,
// too little for the 1e-4 agreement with the double-precision CPU reference on every device.
const float kPi = 3.14159265358979;

vec2 cmul(vec2 a, vec2 b) { return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }
vec2 cdiv(vec2 a, vec2 b) { return cmul(a, vec2(b.x, -b.y)) / dot(b, b); }

vec2 cis(float t) {
  // t = q pi/2 + r, |r| <= pi/4; pi/2 split in three (Cody & Waite) so r keeps its precision.
  const float q = floor(t * 0.636619772367581 + 0.5);
  float r = ((t - q * 1.5703125) - q * 4.837512969970703125e-4) - q * 7.54978995489188216e-8;
  const float r2 = r * r;
  // Minimax polynomials on [-pi/4, pi/4] (Cephes sinf/cosf), error below 1e-7.
  const float s = r + r * r2 * (-1.6666654611e-1 + r2 * (8.3321608736e-3 + r2 * -1.9515295891e-4));
  const float c = 1.0 - 0.5 * r2 +
                  r2 * r2 * (4.166664568298827e-2 + r2 * (-1.388731625493765e-3 + r2 * 2.443315711809948e-5));
  const int k = int(q) & 3;
  if (k == 0) return vec2(c, s);
  if (k == 1) return vec2(-s, c);
  if (k == 2) return vec2(-c, -s);
  return vec2(s, -c);
}
