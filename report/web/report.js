// The report page: summary, mode table and selector, the viewer, each mode's directivity, and
// click-to-strike through WebAudio. window.chladniReport exposes the same actions to scripts
// (the browser tests drive the page through it and through real mouse events).
"use strict";

(() => {
  const R = window.CHLADNI_REPORT;
  const api = { ready: false, errors: [], lastStrike: null, strikes: 0 };
  window.chladniReport = api;
  const $ = (id) => document.getElementById(id);
  const fmt = (x, digits = 4) => (Number.isFinite(x) ? Number(x).toPrecision(digits) : "-");

  const points = R.points.count;
  const pointPos = ChladniStrike.f32(R.points.positions);
  const pointNormal = ChladniStrike.f32(R.points.normals);
  const shapes = ChladniStrike.f32(R.shapes);
  const surface = {
    positions: ChladniStrike.f32(R.surface.positions),
    normals: ChladniStrike.f32(R.surface.normals),
    indices: ChladniStrike.u32(R.surface.indices),
  };
  const pointOf = ChladniStrike.u32(R.surface.point_of_vertex);
  const directivity = ChladniStrike.f32(R.directivity.values);
  let selected = 0;

  function summary() {
    const m = R.material;
    $("title").textContent = `Chladni report: ${R.bank}`;
    $("summary").textContent =
      `${m.name}: E ${fmt(m.E, 3)} Pa, nu ${fmt(m.nu, 3)}, rho ${fmt(m.rho, 4)} kg/m^3, damping ` +
      `${m.damping}. ${R.modes.length} of ${R.bank_modes} modes shown; transfer ${R.transfer}; ` +
      `surface ${R.surface.vertices} vertices, ${R.surface.triangles} triangles; listener at ` +
      `(${R.listener.map((x) => fmt(x, 3)).join(", ")}) m.`;
  }

  function table() {
    const head = ["mode", "freq (Hz)", "decay (1/s)", "damp. ratio", "T60 (s)", "gain at listener",
                  "transfer", "order", "held-out err.", "flags"];
    $("modes").tHead.innerHTML = "<tr>" + head.map((h) => `<th>${h}</th>`).join("") + "</tr>";
    const body = $("modes").tBodies[0];
    R.modes.forEach((m, i) => {
      const t = m.transfer;
      const flags = !t ? "no transfer: compact-source gain"
                   : !t.used_at_runtime ? "POOR FIT (unused: compact-source gain)"
                   : t.poor_fit ? "POOR FIT" : "";
      const row = body.insertRow();
      row.innerHTML =
        [i, fmt(m.frequency_hz, 6), fmt(m.decay_per_s, 3), fmt(m.damping_ratio, 3), fmt(m.t60_s, 3),
         fmt(m.gain, 3), t ? t.method : "-", t ? t.order : "-", t ? fmt(t.held_out_error, 2) : "-"]
          .map((v) => `<td>${v}</td>`).join("") + `<td class="flag">${flags}</td>`;
      row.addEventListener("click", () => selectMode(i));
      const o = document.createElement("option");
      o.value = i;
      o.textContent = `${i}: ${fmt(m.frequency_hz, 5)} Hz`;
      $("mode-select").appendChild(o);
    });
    $("mode-select").addEventListener("change", (e) => selectMode(Number(e.target.value)));
  }

  function shapeOnSurface(mode) {
    const out = new Float32Array(pointOf.length * 3);
    for (let v = 0; v < pointOf.length; ++v) {
      const o = (mode * points + pointOf[v]) * 3;
      out[3 * v] = shapes[o];
      out[3 * v + 1] = shapes[o + 1];
      out[3 * v + 2] = shapes[o + 2];
    }
    return out;
  }

  function drawDirectivity(mode) {
    const c = $("directivity"), g = c.getContext("2d");
    const n = R.directivity.angles, cx = c.width / 2, cy = c.height / 2, r0 = c.width * 0.42;
    g.clearRect(0, 0, c.width, c.height);
    g.strokeStyle = "#d0d0d0";
    g.fillStyle = "#777";
    g.font = "11px sans-serif";
    for (const f of [0.25, 0.5, 0.75, 1]) {
      g.beginPath();
      g.arc(cx, cy, r0 * f, 0, 2 * Math.PI);
      g.stroke();
    }
    const colours = ["#1f77b4", "#2ca02c", "#d62728"];
    R.directivity.planes.forEach((plane, p) => {
      g.strokeStyle = colours[p];
      g.lineWidth = 2;
      g.beginPath();
      for (let a = 0; a <= n; ++a) {
        const v = directivity[(mode * 3 + p) * n + (a % n)], t = (2 * Math.PI * a) / n;
        const x = cx + r0 * v * Math.cos(t), y = cy - r0 * v * Math.sin(t);
        a ? g.lineTo(x, y) : g.moveTo(x, y);
      }
      g.stroke();
      g.fillStyle = colours[p];
      g.fillText(`${plane} plane`, 8, 14 + 14 * p);
    });
    $("directivity-caption").textContent =
      `|p| of mode ${mode} at ${fmt(R.directivity.distance_m, 3)} m on three great circles ` +
      `(angle from the first axis of each plane), scaled to its loudest direction; rings at ` +
      `25 % steps.`;
  }

  function selectMode(i) {
    selected = Math.max(0, Math.min(R.modes.length - 1, i | 0));
    viewer.setShape(shapeOnSurface(selected));
    $("mode-select").value = selected;
    for (const [k, row] of Array.from($("modes").tBodies[0].rows).entries())
      row.classList.toggle("selected", k === selected);
    const m = R.modes[selected];
    $("mode-caption").textContent =
      `${fmt(m.frequency_hz, 6)} Hz, T60 ${fmt(m.t60_s, 3)} s`;
    drawDirectivity(selected);
  }

  function nearestPoint(p) {
    let best = Infinity, k = 0;
    for (let i = 0; i < points; ++i) {
      const dx = pointPos[3 * i] - p[0], dy = pointPos[3 * i + 1] - p[1], dz = pointPos[3 * i + 2] - p[2];
      const d = dx * dx + dy * dy + dz * dz;
      if (d < best) best = d, k = i;
    }
    return k;
  }

  function drawSpectrum(samples, fs) {
    const c = $("spectrum"), g = c.getContext("2d");
    const { db, binHz } = ChladniStrike.spectrum(samples, fs);
    const fmin = 20, fmax = fs / 2, top = Math.max(...db), range = 80;
    const x = (f) => 40 + ((c.width - 50) * Math.log(f / fmin)) / Math.log(fmax / fmin);
    const y = (v) => 10 + ((c.height - 40) * (top - v)) / range;
    g.clearRect(0, 0, c.width, c.height);
    g.strokeStyle = "#999";
    g.strokeRect(40, 10, c.width - 50, c.height - 40);
    g.fillStyle = "#555";
    g.font = "10px sans-serif";
    for (const f of [100, 1000, 10000]) if (f < fmax) g.fillText(f >= 1000 ? `${f / 1000}k` : `${f}`, x(f) - 8, c.height - 18);
    g.fillText("Hz", c.width - 24, c.height - 6);
    for (const v of [0, -20, -40, -60]) g.fillText(`${v}`, 8, y(top + v) + 4);
    g.fillText("dB", 8, c.height - 6);
    g.strokeStyle = "#e07b00";
    for (const m of R.modes) {  // the bank's frequencies, for comparison
      g.beginPath();
      g.moveTo(x(m.frequency_hz), 10);
      g.lineTo(x(m.frequency_hz), 16);
      g.stroke();
    }
    g.strokeStyle = "#1f4e9e";
    g.beginPath();
    for (let k = 1; k < db.length; ++k) {
      const f = k * binHz;
      if (f < fmin) continue;
      const px = x(f), py = Math.min(c.height - 30, y(db[k]));
      k === 1 || f - binHz < fmin ? g.moveTo(px, py) : g.lineTo(px, py);
    }
    g.stroke();
  }

  // Synthesizes the strike, renders it through an OfflineAudioContext (normalized to -1 dBFS),
  // and plays the result when asked.
  async function strike(hit) {
    const t0 = performance.now();
    const point = nearestPoint(hit.point);
    const n = [pointNormal[3 * point], pointNormal[3 * point + 1], pointNormal[3 * point + 2]];
    const direction = n.map((x) => -x);  // into the surface
    const s = R.strike;
    const raw = ChladniStrike.synthesize(R.modes, shapes, points, point, direction, {
      sampleRate: s.sample_rate, contactTime: s.contact_time, impulse: s.impulse, maxSeconds: 4,
    });
    let peak = 0;
    for (const v of raw) peak = Math.max(peak, Math.abs(v));
    const ctx = new OfflineAudioContext(1, raw.length, s.sample_rate);
    const buffer = ctx.createBuffer(1, raw.length, s.sample_rate);
    buffer.copyToChannel(raw, 0);
    const src = ctx.createBufferSource(), gain = ctx.createGain();
    src.buffer = buffer;
    gain.gain.value = peak > 0 ? 0.89 / peak : 0;
    src.connect(gain).connect(ctx.destination);
    src.start();
    const rendered = await ctx.startRendering();
    const samples = rendered.getChannelData(0);
    const ms = performance.now() - t0;
    api.lastStrike = { point, position: hit.point, direction, sampleRate: s.sample_rate,
                       peakPa: peak, samples, ms };
    api.strikes += 1;
    $("strike-info").textContent =
      `Struck at surface point ${point} (${hit.point.map((v) => fmt(v, 3)).join(", ")}) m with ` +
      `${s.impulse} N s over ${s.contact_time * 1e3} ms: peak ${fmt(peak, 3)} Pa at the listener ` +
      `(played normalized; ${raw.length} samples from ${R.modes.length} modes in ` +
      `${Math.round(ms)} ms). Orange ticks: the bank's frequencies.`;
    drawSpectrum(samples, s.sample_rate);
    if ($("play").checked) play(rendered);
  }

  let live = null;
  function play(buffer) {
    try {
      live = live || new AudioContext();
      const src = live.createBufferSource();
      src.buffer = buffer;
      src.connect(live.destination);
      src.start();
    } catch (e) {
      $("strike-info").textContent += ` (No audio output: ${e.message})`;
    }
  }

  let viewer = null;
  try {
    summary();
    viewer = new ChladniViewer($("view"), surface, R.centre, R.radius_m, (hit) => {
      strike(hit).catch((e) => { api.errors.push(String(e)); $("strike-info").textContent = String(e); });
    });
    table();
    selectMode(0);
    $("animate").addEventListener("change", (e) => { viewer.animate = e.target.checked; });
    Object.assign(api, {
      viewer,
      selectMode,
      selected: () => selected,
      // Stops the animation at a phase (radians), so two pictures compare.
      freeze: (phase) => { viewer.animate = false; viewer.phase = phase; viewer.draw(); },
      // Canvas-relative CSS pixel of model point i, and the canvas's page offset.
      pixelOfPoint: (i) => viewer.project([pointPos[3 * i], pointPos[3 * i + 1], pointPos[3 * i + 2]]),
      canvasOffset: () => { const r = $("view").getBoundingClientRect(); return [r.left, r.top]; },
      strike,
    });
    // index.html#mode=N&strike=P opens on mode N and strikes surface point P (links, figures).
    const hash = new URLSearchParams(location.hash.slice(1));
    if (hash.has("mode")) selectMode(Number(hash.get("mode")));
    const p = Number(hash.get("strike"));
    if (hash.has("strike") && p >= 0 && p < points)
      strike({ point: [pointPos[3 * p], pointPos[3 * p + 1], pointPos[3 * p + 2]] })
        .catch((e) => api.errors.push(String(e)));
    api.ready = true;
  } catch (e) {
    api.errors.push(String(e));
    document.body.insertAdjacentHTML("afterbegin", `<p class="flag">${String(e)}</p>`);
    throw e;
  }
})();
