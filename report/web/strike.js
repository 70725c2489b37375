// The sound of a strike, computed as the runtime computes it (DESIGN.md, runtime/modal/impact):
// mode i of a strike with impulse J along unit direction n at surface point x responds as
//   q_i(t) = Im(W_i(t) exp(lambda_i t)) (v_i(x) . n) J / omega_d,   lambda_i = -d_i + i omega_d,
// where W_i(t) = integral_0^min(t,tau) F(s) exp(-lambda_i s) ds / J for the half-sine contact
// force F of duration tau, and the listener hears sum_i gain_i q_i(t).
"use strict";

const ChladniStrike = (() => {
  function decode(base64) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
    return bytes.buffer;
  }
  const f32 = (s) => new Float32Array(decode(s));
  const u32 = (s) => new Uint32Array(decode(s));

  // Complex numbers as [re, im].
  const mul = (a, b) => [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]];
  const div = (a, b) => {
    const d = b[0] * b[0] + b[1] * b[1];
    return [(a[0] * b[0] + a[1] * b[1]) / d, (a[1] * b[0] - a[0] * b[1]) / d];
  };
  const cexp = (a) => {
    const m = Math.exp(a[0]);
    return [m * Math.cos(a[1]), m * Math.sin(a[1])];
  };

  // W(t) for J = 1: closed form of (b/2) int_0^t sin(b s) exp(-lambda s) ds, b = pi / tau, as
  // (b/2) (b - exp(-lambda t) (lambda sin(b t) + b cos(b t))) / (lambda^2 + b^2); at t = tau it is
  // b^2 (1 + exp(-lambda tau)) / (2 (lambda^2 + b^2)), impact.cpp's contact_weight.
  function contactWeight(tau, omegaD, decay, t) {
    if (!(tau > 0)) return [1, 0];
    t = Math.min(t, tau);
    const lambda = [-decay, omegaD];
    const b = Math.PI / tau;
    const l2 = mul(lambda, lambda);
    const den = [l2[0] + b * b, l2[1]];
    if (Math.hypot(den[0], den[1]) > 1e-6 * b * b) {
      const e = cexp([-lambda[0] * t, -lambda[1] * t]);
      const inner = [lambda[0] * Math.sin(b * t) + b * Math.cos(b * t), lambda[1] * Math.sin(b * t)];
      const num = mul(e, inner);
      return div([(b / 2) * (b - num[0]), (-b / 2) * num[1]], den);
    }
    // Near resonance the closed form is 0/0: Simpson's rule, as the runtime does.
    const n = 256;
    let sum = [0, 0];
    for (let k = 0; k <= n; ++k) {
      const s = (t * k) / n;
      const w = k === 0 || k === n ? 1 : k % 2 ? 4 : 2;
      const e = cexp([-lambda[0] * s, -lambda[1] * s]);
      const f = w * 0.5 * b * Math.sin(b * s);
      sum = [sum[0] + f * e[0], sum[1] + f * e[1]];
    }
    return [(sum[0] * t) / (3 * n), (sum[1] * t) / (3 * n)];
  }

  // Samples of the strike at model point `point` along `direction` (unit), from t = 0 (contact
  // start). `modes`: [{omega_d, decay_per_s, gain}], `shapes`: Float32Array [mode][point][3].
  function synthesize(modes, shapes, pointCount, point, direction, opts) {
    const fs = opts.sampleRate, tau = opts.contactTime, J = opts.impulse;
    let longest = 0.5;
    for (const m of modes)
      if (m.decay_per_s > 0) longest = Math.max(longest, Math.log(1000) / m.decay_per_s);
    const seconds = Math.min(opts.maxSeconds || 4, longest + tau);
    const n = Math.max(1, Math.round(seconds * fs));
    const out = new Float64Array(n);
    const contactSamples = Math.min(n, Math.ceil(tau * fs));
    for (let i = 0; i < modes.length; ++i) {
      const m = modes[i];
      if (!(m.omega_d > 0)) continue;
      const o = (i * pointCount + point) * 3;
      const vn = shapes[o] * direction[0] + shapes[o + 1] * direction[1] + shapes[o + 2] * direction[2];
      const amp = (m.gain * vn * J) / m.omega_d;
      if (amp === 0) continue;
      const lambda = [-m.decay_per_s, m.omega_d];
      for (let k = 0; k < contactSamples; ++k) {  // during the contact: W grows with t
        const t = k / fs;
        const z = mul(contactWeight(tau, m.omega_d, m.decay_per_s, t), cexp([lambda[0] * t, lambda[1] * t]));
        out[k] += amp * z[1];
      }
      // After it: z advances by exp(lambda / fs) per sample (in double precision).
      const step = cexp([lambda[0] / fs, lambda[1] / fs]);
      const t0 = contactSamples / fs;
      let z = mul(contactWeight(tau, m.omega_d, m.decay_per_s, tau), cexp([lambda[0] * t0, lambda[1] * t0]));
      for (let k = contactSamples; k < n; ++k) {
        out[k] += amp * z[1];
        z = mul(z, step);
        if ((k & 4095) === 0 && Math.abs(z[0]) + Math.abs(z[1]) < 1e-12) break;
      }
    }
    return Float32Array.from(out);
  }

  // In-place radix-2 FFT of (re, im), length a power of two.
  function fft(re, im) {
    const n = re.length;
    for (let i = 1, j = 0; i < n; ++i) {
      let bit = n >> 1;
      for (; j & bit; bit >>= 1) j ^= bit;
      j ^= bit;
      if (i < j) {
        [re[i], re[j]] = [re[j], re[i]];
        [im[i], im[j]] = [im[j], im[i]];
      }
    }
    for (let len = 2; len <= n; len <<= 1) {
      const a = (-2 * Math.PI) / len;
      for (let i = 0; i < n; i += len)
        for (let k = 0; k < len / 2; ++k) {
          const c = Math.cos(a * k), s = Math.sin(a * k);
          const p = i + k, q = p + len / 2;
          const tr = re[q] * c - im[q] * s, ti = re[q] * s + im[q] * c;
          re[q] = re[p] - tr;
          im[q] = im[p] - ti;
          re[p] += tr;
          im[p] += ti;
        }
    }
  }

  // Hann-windowed power spectrum (dB) of the first 2^k samples (at most `maxSize`).
  function spectrum(samples, sampleRate, maxSize = 65536) {
    let n = 1024;
    while (n * 2 <= Math.min(samples.length, maxSize)) n *= 2;
    const re = new Float64Array(n), im = new Float64Array(n);
    for (let i = 0; i < n && i < samples.length; ++i)
      re[i] = samples[i] * (0.5 - 0.5 * Math.cos((2 * Math.PI * (i + 0.5)) / n));
    fft(re, im);
    const db = new Float64Array(n / 2 + 1);
    for (let k = 0; k <= n / 2; ++k) db[k] = 10 * Math.log10(re[k] * re[k] + im[k] * im[k] + 1e-30);
    return { db, binHz: sampleRate / n };
  }

  return { f32, u32, contactWeight, synthesize, spectrum };
})();
