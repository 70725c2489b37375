// A small WebGL viewer: the surface lit from the camera, displaced along a mode shape and
// coloured by its displacement magnitude; drag to orbit, scroll to zoom, click to pick a point
// (a ray against the undeformed triangles).
"use strict";

class ChladniViewer {
  constructor(canvas, surface, centre, radius, onPick) {
    this.canvas = canvas;
    this.positions = surface.positions;
    this.indices = surface.indices;
    this.centre = centre;
    this.radius = radius > 0 ? radius : 1;
    this.onPick = onPick;
    this.yaw = 0.7;
    this.pitch = 0.45;
    this.distance = 3.2 * this.radius;
    this.phase = Math.PI / 2;
    this.animate = true;
    this.amplitude = 0;
    this.maxShape = 1;
    const opts = { antialias: true, preserveDrawingBuffer: true };
    const gl = canvas.getContext("webgl2", opts) || canvas.getContext("webgl", opts);
    if (!gl) throw new Error("this browser has no WebGL");
    this.gl = gl;
    if (!(gl instanceof WebGL2RenderingContext) && !gl.getExtension("OES_element_index_uint"))
      throw new Error("WebGL lacks 32-bit indices (OES_element_index_uint)");
    this.program = this.compile();
    this.buffers = {
      position: this.upload(gl.ARRAY_BUFFER, surface.positions),
      normal: this.upload(gl.ARRAY_BUFFER, surface.normals),
      shape: this.upload(gl.ARRAY_BUFFER, new Float32Array(surface.positions.length)),
      index: this.upload(gl.ELEMENT_ARRAY_BUFFER, surface.indices),
    };
    this.listen();
    const frame = (ms) => {
      if (this.animate) this.phase = (ms / 1000) * 2 * Math.PI * 0.7;
      this.draw();
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
  }

  compile() {
    const gl = this.gl;
    const vs = `
      attribute vec3 aPosition, aNormal, aShape;
      uniform mat4 uViewProj;
      uniform float uDisplace, uMaxShape;
      varying float vMag;
      varying vec3 vNormal;
      void main() {
        vMag = length(aShape) / uMaxShape;
        vNormal = aNormal;
        gl_Position = uViewProj * vec4(aPosition + uDisplace * aShape, 1.0);
      }`;
    const fs = `
      precision mediump float;
      uniform vec3 uEye;
      varying float vMag;
      varying vec3 vNormal;
      vec3 ramp(float u) {  // dark blue, teal, green, yellow
        u = clamp(u, 0.0, 1.0);
        vec3 a = vec3(0.19, 0.07, 0.43), b = vec3(0.13, 0.57, 0.55), c = vec3(0.99, 0.91, 0.14);
        return u < 0.5 ? mix(a, b, u * 2.0) : mix(b, c, u * 2.0 - 1.0);
      }
      void main() {
        float light = 0.35 + 0.65 * abs(dot(normalize(vNormal), uEye));
        gl_FragColor = vec4(ramp(vMag) * light, 1.0);
      }`;
    const shader = (type, src) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      return s;
    };
    const p = gl.createProgram();
    gl.attachShader(p, shader(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    return p;
  }

  upload(target, data) {
    const gl = this.gl, b = gl.createBuffer();
    gl.bindBuffer(target, b);
    gl.bufferData(target, data, gl.STATIC_DRAW);
    return b;
  }

  // Per-vertex shape (3 floats each); the largest motion drawn is 6 % of the object's size.
  setShape(shape) {
    const gl = this.gl;
    let top = 0;
    for (let i = 0; i < shape.length; i += 3)
      top = Math.max(top, Math.hypot(shape[i], shape[i + 1], shape[i + 2]));
    this.maxShape = top > 0 ? top : 1;
    this.amplitude = (0.06 * 2 * this.radius) / this.maxShape;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers.shape);
    gl.bufferData(gl.ARRAY_BUFFER, shape, gl.STATIC_DRAW);
  }

  eye() {
    const c = Math.cos(this.pitch);
    return [c * Math.cos(this.yaw), c * Math.sin(this.yaw), Math.sin(this.pitch)];
  }

  // Column-major view-projection matrix, z up.
  viewProj() {
    const e = this.eye(), d = this.distance;
    const pos = [this.centre[0] + d * e[0], this.centre[1] + d * e[1], this.centre[2] + d * e[2]];
    const f = [-e[0], -e[1], -e[2]];
    let s = [f[1], -f[0], 0];  // f x z
    const sl = Math.hypot(s[0], s[1]) || 1;
    s = [s[0] / sl, s[1] / sl, 0];
    const u = [s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const view = [s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
                  -dot(s, pos), -dot(u, pos), dot(f, pos), 1];
    const aspect = this.canvas.width / this.canvas.height, fov = (35 * Math.PI) / 180;
    const near = Math.max(1e-4, d - 3 * this.radius), far = d + 3 * this.radius;
    const t = 1 / Math.tan(fov / 2);
    const proj = [t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1,
                  0, 0, (2 * far * near) / (near - far), 0];
    const m = new Float32Array(16);
    for (let c = 0; c < 4; ++c)
      for (let r = 0; r < 4; ++r) {
        let v = 0;
        for (let k = 0; k < 4; ++k) v += proj[k * 4 + r] * view[c * 4 + k];
        m[c * 4 + r] = v;
      }
    return { m, pos, s, u, f, t, aspect };
  }

  draw() {
    const gl = this.gl, p = this.program;
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(0.94, 0.95, 0.96, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(p);
    const attrib = (name, buffer) => {
      const loc = gl.getAttribLocation(p, name);
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
    };
    attrib("aPosition", this.buffers.position);
    attrib("aNormal", this.buffers.normal);
    attrib("aShape", this.buffers.shape);
    const vp = this.viewProj();
    gl.uniformMatrix4fv(gl.getUniformLocation(p, "uViewProj"), false, vp.m);
    gl.uniform1f(gl.getUniformLocation(p, "uDisplace"), this.amplitude * Math.sin(this.phase));
    gl.uniform1f(gl.getUniformLocation(p, "uMaxShape"), this.maxShape);
    gl.uniform3fv(gl.getUniformLocation(p, "uEye"), this.eye());
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.buffers.index);
    gl.drawElements(gl.TRIANGLES, this.indices.length, gl.UNSIGNED_INT, 0);
  }

  // Canvas pixel (CSS px from its top left) -> nearest hit {point, triangle} or null.
  pick(x, y) {
    const vp = this.viewProj();
    const nx = ((2 * x) / this.canvas.clientWidth - 1) / (vp.t / vp.aspect);
    const ny = (1 - (2 * y) / this.canvas.clientHeight) / vp.t;
    const dir = [0, 1, 2].map((k) => vp.f[k] + nx * vp.s[k] + ny * vp.u[k]);
    const P = this.positions, I = this.indices, o = vp.pos;
    let best = Infinity, hit = null;
    for (let t = 0; t < I.length; t += 3) {  // Moller-Trumbore
      const a = I[t] * 3, b = I[t + 1] * 3, c = I[t + 2] * 3;
      const e1 = [P[b] - P[a], P[b + 1] - P[a + 1], P[b + 2] - P[a + 2]];
      const e2 = [P[c] - P[a], P[c + 1] - P[a + 1], P[c + 2] - P[a + 2]];
      const pv = [dir[1] * e2[2] - dir[2] * e2[1], dir[2] * e2[0] - dir[0] * e2[2],
                  dir[0] * e2[1] - dir[1] * e2[0]];
      const det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
      if (Math.abs(det) < 1e-18) continue;
      const tv = [o[0] - P[a], o[1] - P[a + 1], o[2] - P[a + 2]];
      const u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
      if (u < 0 || u > 1) continue;
      const q = [tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2],
                 tv[0] * e1[1] - tv[1] * e1[0]];
      const v = (dir[0] * q[0] + dir[1] * q[1] + dir[2] * q[2]) / det;
      if (v < 0 || u + v > 1) continue;
      const dist = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
      if (dist > 0 && dist < best) {
        best = dist;
        hit = { triangle: t / 3, point: [0, 1, 2].map((k) => o[k] + dist * dir[k]) };
      }
    }
    return hit;
  }

  // Where a world point appears on the canvas (CSS px from its top left).
  project(p) {
    const m = this.viewProj().m;
    const clip = [0, 1, 2, 3].map((r) => m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r]);
    return [((clip[0] / clip[3] + 1) / 2) * this.canvas.clientWidth,
            ((1 - clip[1] / clip[3]) / 2) * this.canvas.clientHeight];
  }

  listen() {
    const c = this.canvas;
    let down = null;
    c.addEventListener("mousedown", (e) => { down = { x: e.offsetX, y: e.offsetY, moved: 0 }; });
    c.addEventListener("mousemove", (e) => {
      if (!down || !(e.buttons & 1)) return;
      down.moved += Math.abs(e.movementX) + Math.abs(e.movementY);
      this.yaw -= e.movementX * 0.01;
      this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + e.movementY * 0.01));
    });
    c.addEventListener("mouseup", (e) => {
      if (down && down.moved < 4) {
        const hit = this.pick(e.offsetX, e.offsetY);
        if (hit) this.onPick(hit);
      }
      down = null;
    });
    c.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.distance = Math.max(1.2 * this.radius, Math.min(20 * this.radius,
                                                          this.distance * Math.exp(e.deltaY * 0.001)));
    }, { passive: false });
  }
}
