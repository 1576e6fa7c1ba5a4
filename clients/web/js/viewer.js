// The dashboard's particle viewer: a small WebGL renderer written for this page (no library,
// nothing fetched from elsewhere, so the dashboard works offline). Particles are points
// coloured by one value with viridis (the colour map of the PNG previews); a 3D result turns
// with the mouse (drag: orbit, shift-drag or right-drag: pan, wheel: zoom, double-click:
// reset); 2D results are seen face on (drag pans), and a 1D result is drawn as its profile,
// the value upwards, like its preview.

// matplotlib's viridis at 0, 1/8, ..., 1 (the colour bar uses the same stops).
export const VIRIDIS = [[68, 1, 84], [71, 45, 123], [59, 82, 139], [44, 114, 142], [33, 145, 140],
                              [40, 174, 128], [94, 201, 98], [173, 220, 48], [253, 231, 37]];
const GRADIENT = `linear-gradient(to right, ${VIRIDIS.map(([r, g, b], i) =>
  `rgb(${r}, ${g}, ${b}) ${(i * 100) / (VIRIDIS.length - 1)}%`).join(", ")})`;
const FOV = (40 * Math.PI) / 180;

const POINT_VERTEX = `
  attribute vec3 a_position;
  attribute float a_value;
  uniform mat4 u_view, u_projection;
  uniform vec2 u_range;
  uniform float u_size, u_scale;
  uniform bool u_ortho;
  uniform vec3 u_colours[9];
  varying vec3 v_colour;
  void main() {
    vec4 eye = u_view * vec4(a_position, 1.0);
    gl_Position = u_projection * eye;
    float depth = u_ortho ? 1.0 : max(-eye.z, 1e-9);
    gl_PointSize = clamp(u_size * u_scale / depth, 1.5, 48.0);
    // viridis by pieces: after step k the colour is stop k+1 for x past it, else unchanged
    float x = 8.0 * clamp((a_value - u_range.x) / max(u_range.y - u_range.x, 1e-30), 0.0, 1.0);
    vec3 colour = u_colours[0];
    for (int k = 0; k < 8; k++) colour = mix(colour, u_colours[k + 1], clamp(x - float(k), 0.0, 1.0));
    v_colour = colour;
  }`;
const POINT_FRAGMENT = `
  precision mediump float;
  uniform bool u_round;
  varying vec3 v_colour;
  void main() {
    vec2 d = 2.0 * gl_PointCoord - 1.0;
    float r2 = dot(d, d);
    if (u_round && r2 > 1.0) discard;
    // round points are lit as small spheres (light from the viewer): depth is readable
    float light = u_round ? 0.55 + 0.45 * sqrt(1.0 - min(r2, 1.0)) : 1.0;
    gl_FragColor = vec4(v_colour * light, 1.0);
  }`;
const LINE_VERTEX = `
  attribute vec3 a_position;
  uniform mat4 u_view, u_projection;
  void main() { gl_Position = u_projection * u_view * vec4(a_position, 1.0); }`;
const LINE_FRAGMENT = `
  precision mediump float;
  void main() { gl_FragColor = vec4(0.55, 0.58, 0.63, 1.0); }`;

// ------------------------------------------------------------ 4x4 matrices, column-major

function perspective(fovy, aspect, near, far) {
  const f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
  return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
}

function orthographic(left, right, bottom, top, near, far) {
  return new Float32Array([2 / (right - left), 0, 0, 0, 0, 2 / (top - bottom), 0, 0, 0, 0, -2 / (far - near), 0,
    -(right + left) / (right - left), -(top + bottom) / (top - bottom), -(far + near) / (far - near), 1]);
}

const sub = (a, b) => a.map((v, i) => v - b[i]);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const normalize = (a) => { const n = Math.hypot(...a) || 1; return a.map((v) => v / n); };

function lookAt(eye, target, up) {
  const z = normalize(sub(eye, target)), x = normalize(cross(up, z)), y = cross(z, x);
  return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
    -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
}

function transform(m, p) {  // m * (p, 1)
  return [0, 1, 2, 3].map((r) => m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r]);
}

// ------------------------------------------------------------ WebGL plumbing

function program(gl, vertex, fragment) {
  const shader = (type, source) => {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  };
  const p = gl.createProgram();
  gl.attachShader(p, shader(gl.VERTEX_SHADER, vertex));
  gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fragment));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  const uniforms = {}, attributes = {};
  for (let i = 0; i < gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS); i += 1) {
    const name = gl.getActiveUniform(p, i).name.replace(/\[0\]$/, "");
    uniforms[name] = gl.getUniformLocation(p, name);
  }
  for (let i = 0; i < gl.getProgramParameter(p, gl.ACTIVE_ATTRIBUTES); i += 1) {
    const name = gl.getActiveAttrib(p, i).name;
    attributes[name] = gl.getAttribLocation(p, name);
  }
  return { program: p, uniforms, attributes };
}

/** The edges of the box lower..upper (a segment in 1D, a rectangle in 2D), as line pairs. */
function boxEdges(lower, upper, dimension) {
  const corner = (bits) => [0, 1, 2].map((a) => (bits >> a) & 1 ? upper[a] : lower[a]);
  const edges = [];
  const corners = 1 << dimension;
  for (let c = 0; c < corners; c += 1) {
    for (let a = 0; a < dimension; a += 1) {
      if (!((c >> a) & 1)) edges.push(...corner(c), ...corner(c | (1 << a)));
    }
  }
  return new Float32Array(edges);
}

/** True when this browser can draw WebGL (headless browsers without a GPU may not). */
export function supported() {
  try {
    return Boolean(document.createElement("canvas").getContext("webgl"));
  } catch (_) {
    return false;
  }
}

// ------------------------------------------------------------ the viewer

const HOME = { yaw: -0.6, pitch: 0.45, zoom: 1 };

/**
 * A viewer in `container`. `options`: dimension, lower and upper (the box shown, 3 numbers
 * each; a 1D profile's second axis is the value), up (the axis drawn upwards, 0..2), axes
 * (the axis labels), spacing (the particles' spacing: the size of a point).
 */
export class Viewer {
  constructor(container, options) {
    this.options = options;
    this.canvas = document.createElement("canvas");
    this.canvas.className = "viewer-canvas";
    this.canvas.setAttribute("aria-label", "particle viewer");
    this.labels = options.axes.map((text) => {
      const label = document.createElement("span");
      label.className = "viewer-axis";
      label.textContent = text;
      return label;
    });
    container.replaceChildren(this.canvas, ...this.labels);
    const gl = this.canvas.getContext("webgl", { antialias: true, preserveDrawingBuffer: true });
    if (!gl) throw new Error("WebGL is not available in this browser");
    this.gl = gl;
    this.points = program(gl, POINT_VERTEX, POINT_FRAGMENT);
    this.lines = program(gl, LINE_VERTEX, LINE_FRAGMENT);
    this.buffers = { position: gl.createBuffer(), value: gl.createBuffer(), box: gl.createBuffer() };
    this.dimension = options.dimension;
    this.lower = options.lower.slice();
    this.upper = options.upper.slice();
    const { dimension, lower, upper } = this;
    this.edges = boxEdges(lower, upper, Math.max(dimension, dimension === 1 ? 2 : dimension));
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers.box);
    gl.bufferData(gl.ARRAY_BUFFER, this.edges, gl.STATIC_DRAW);
    this.centre = [0, 1, 2].map((a) => (lower[a] + upper[a]) / 2);
    this.radius = Math.max(1e-30, Math.hypot(...[0, 1, 2].map((a) => (upper[a] - lower[a]) / 2)));
    this.camera = { ...HOME, pan: [0, 0, 0] };
    Object.assign(this, { count: 0, range: [0, 1], frameRequested: false });
    // the axis drawn upwards and the two across it, as unit vectors
    this.up = [0, 1, 2].map((a) => (a === options.up ? 1 : 0));
    this.across = [[0, 1, 2].map((a) => (a === (options.up + 1) % 3 ? 1 : 0)),
                   [0, 1, 2].map((a) => (a === (options.up + 2) % 3 ? 1 : 0))];
    this.bindMouse();
    this.resize = new ResizeObserver(() => this.redraw());
    this.resize.observe(this.canvas);
  }

  matrices() {
    const { canvas, camera, centre, radius, lower, upper } = this;
    const aspect = canvas.width / Math.max(1, canvas.height);
    const target = centre.map((c, a) => c + camera.pan[a]);
    if (this.dimension === 3) {
      const distance = (radius / Math.sin(FOV / 2)) * 1.05 * camera.zoom;
      const horizontal = this.across[0].map((v, a) => v * Math.cos(camera.yaw) + this.across[1][a] * Math.sin(camera.yaw));
      const eye = target.map((t, a) => t + distance * (Math.cos(camera.pitch) * horizontal[a] + Math.sin(camera.pitch) * this.up[a]));
      return { view: lookAt(eye, target, this.up), projection: perspective(FOV, aspect, distance / 100, distance * 10),
               scale: canvas.height / (2 * Math.tan(FOV / 2)), ortho: false };
    }
    // 1D and 2D: face on, x to the right and y upwards
    const half = 0.6 * Math.max((upper[1] - lower[1]), (upper[0] - lower[0]) / aspect) * camera.zoom;
    const view = lookAt([target[0], target[1], target[2] + radius * 4], target, [0, 1, 0]);
    return { view, projection: orthographic(-half * aspect, half * aspect, -half, half, radius, radius * 8),
             scale: canvas.height / (2 * half), ortho: true };
  }

  draw() {
    const { gl, canvas } = this;
    this.frameRequested = false;
    const ratio = window.devicePixelRatio || 1;
    const width = Math.round(canvas.clientWidth * ratio), height = Math.round(canvas.clientHeight * ratio);
    if (canvas.width !== width || canvas.height !== height) { canvas.width = width; canvas.height = height; }
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(0.97, 0.975, 0.98, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    const { view, projection, scale, ortho } = this.matrices();
    this.drawBox(view, projection);
    if (this.count) this.drawPoints(view, projection, scale, ortho);
    this.placeLabels((p) => transform(projection, transform(view, p)));
  }

  drawBox(view, projection) {
    const { gl, lines } = this;
    gl.useProgram(lines.program);
    gl.uniformMatrix4fv(lines.uniforms.u_view, false, view);
    gl.uniformMatrix4fv(lines.uniforms.u_projection, false, projection);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers.box);
    gl.enableVertexAttribArray(lines.attributes.a_position);
    gl.vertexAttribPointer(lines.attributes.a_position, 3, gl.FLOAT, false, 0, 0);
    gl.drawArrays(gl.LINES, 0, this.edges.length / 3);
  }

  drawPoints(view, projection, scale, ortho) {
    const { gl, points } = this;
    const u = points.uniforms;
    gl.useProgram(points.program);
    gl.uniformMatrix4fv(u.u_view, false, view);
    gl.uniformMatrix4fv(u.u_projection, false, projection);
    gl.uniform2f(u.u_range, this.range[0], this.range[1]);
    // 2D squares a little larger than the spacing, so that a body has no seams (as the previews)
    gl.uniform1f(u.u_size, this.options.spacing * (this.dimension === 2 ? 1.1 : 1));
    gl.uniform1f(u.u_scale, scale);
    gl.uniform1i(u.u_ortho, ortho ? 1 : 0);
    gl.uniform1i(u.u_round, this.dimension === 2 ? 0 : 1);  // 2D: squares, no seams (as the previews)
    gl.uniform3fv(u.u_colours, new Float32Array(VIRIDIS.flat().map((c) => c / 255)));
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers.position);
    gl.enableVertexAttribArray(points.attributes.a_position);
    gl.vertexAttribPointer(points.attributes.a_position, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers.value);
    gl.enableVertexAttribArray(points.attributes.a_value);
    gl.vertexAttribPointer(points.attributes.a_value, 1, gl.FLOAT, false, 0, 0);
    gl.drawArrays(gl.POINTS, 0, this.count);
  }

  /** Each axis label by the middle of one of the box's edges along it: in 3D the edge drawn
   *  lowest on the screen (the one in front, below the particles), or for the upward axis the
   *  leftmost; in 1D and 2D the bottom and the left edge. */
  placeLabels(project) {
    const { canvas, lower, upper, dimension } = this;
    const width = canvas.clientWidth, height = canvas.clientHeight;
    const toScreen = (point) => {
      const clip = project(point);
      return [((clip[0] / clip[3] + 1) / 2) * width, ((1 - clip[1] / clip[3]) / 2) * height];
    };
    this.labels.forEach((label, axis) => {
      const others = [0, 1, 2].filter((a) => a !== axis).slice(0, dimension === 3 ? 2 : 0);
      let best = null;
      for (let corner = 0; corner < (1 << others.length); corner += 1) {
        const at = lower.slice();
        at[axis] = (lower[axis] + upper[axis]) / 2;
        others.forEach((a, k) => { if ((corner >> k) & 1) at[a] = upper[a]; });
        const screen = toScreen(at);
        const score = dimension === 3 && axis === this.options.up ? -screen[0] : screen[1];
        if (!best || score > best.score) best = { screen, score };
      }
      const vertical = dimension === 3 ? axis === this.options.up : axis === 1;
      const [x, y] = best.screen;
      label.style.left = `${Math.round(x + (vertical ? -10 : 0))}px`;
      label.style.top = `${Math.round(y + (vertical ? 0 : 16))}px`;
      label.classList.toggle("vertical", vertical);
    });
  }

  redraw() {
    if (!this.frameRequested) { this.frameRequested = true; requestAnimationFrame(() => this.draw()); }
  }

  /** New particles: xyz (Float32Array, 3 a particle), one value each and the colour range. */
  show(xyz, values, valueRange) {
    const { gl, lower, upper } = this;
    let position = xyz;
    if (this.dimension === 1) {  // the profile: the value upwards, scaled into the box
      position = new Float32Array(xyz);
      const span = valueRange[1] - valueRange[0] || 1;
      for (let i = 0; i < values.length; i += 1) {
        position[3 * i + 1] = lower[1] + ((values[i] - valueRange[0]) / span) * (upper[1] - lower[1]);
      }
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers.position);
    gl.bufferData(gl.ARRAY_BUFFER, position, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffers.value);
    gl.bufferData(gl.ARRAY_BUFFER, values, gl.DYNAMIC_DRAW);
    this.count = values.length;
    this.range = valueRange;
    this.redraw();
  }

  /** Mouse: drag orbits (3D) or pans (shift-drag, right-drag, and always in 1D and 2D); the wheel
   *  zooms; a double click goes back to the first view. */
  bindMouse() {
    const canvas = this.canvas;
    let drag = null;
    canvas.addEventListener("contextmenu", (event) => event.preventDefault());
    canvas.addEventListener("pointerdown", (event) => {
      drag = { x: event.clientX, y: event.clientY, pan: this.dimension < 3 || event.shiftKey || event.button === 2 };
      canvas.setPointerCapture(event.pointerId);
    });
    canvas.addEventListener("pointerup", () => { drag = null; });
    canvas.addEventListener("pointermove", (event) => {
      if (!drag) return;
      const dx = event.clientX - drag.x, dy = event.clientY - drag.y;
      drag.x = event.clientX;
      drag.y = event.clientY;
      if (drag.pan) this.pan(dx, dy);
      else {
        this.camera.yaw -= dx * 0.01;
        this.camera.pitch = Math.max(-1.55, Math.min(1.55, this.camera.pitch + dy * 0.01));
      }
      this.redraw();
    });
    canvas.addEventListener("wheel", (event) => {
      event.preventDefault();
      this.camera.zoom = Math.max(0.05, Math.min(20, this.camera.zoom * Math.exp(event.deltaY * 0.001)));
      this.redraw();
    }, { passive: false });
    canvas.addEventListener("dblclick", () => { Object.assign(this.camera, { ...HOME, pan: [0, 0, 0] }); this.redraw(); });
  }

  /** Move the target by a drag of dx, dy pixels: the scene follows the pointer. */
  pan(dx, dy) {
    const { view, scale, ortho } = this.matrices();
    const ratio = window.devicePixelRatio || 1;
    const perPixel = ortho ? ratio / scale : ((this.radius / Math.sin(FOV / 2)) * this.camera.zoom * ratio) / scale;
    const right = [view[0], view[4], view[8]], screenUp = [view[1], view[5], view[9]];
    this.camera.pan = this.camera.pan.map((p, a) => p - (dx * right[a] - dy * screenUp[a]) * perPixel);
  }

  destroy() {
    this.resize.disconnect();
    this.gl.getExtension("WEBGL_lose_context")?.loseContext();
  }
}

/** A colour bar: the viridis gradient, its range and the label (with the unit). */
export function colourBar(bar, label, range, format) {
  bar.replaceChildren();
  const strip = document.createElement("div");
  strip.className = "colour-strip";
  strip.style.background = GRADIENT;
  const ends = document.createElement("div");
  ends.className = "colour-ends";
  const low = document.createElement("span"), title = document.createElement("span"), high = document.createElement("span");
  low.textContent = format(range[0]);
  title.textContent = label;
  title.className = "colour-label";
  high.textContent = format(range[1]);
  ends.append(low, title, high);
  bar.append(strip, ends);
}
