// The job page's results card: a WebGL viewer, the PNG image or the animation of the frames the
// result holds (the count and times come from the result, GET .../frames).
import { ACTIVE, ApiError, ConnectionLost, api, fetchBlob, jobUrl } from "./api.js";
import { h, saveBlob } from "./dom.js";
import { fmtNumber } from "./format.js";
import * as viewer from "./viewer.js";

const RESULT_MODES = [["viewer", "Viewer"], ["image", "Image"], ["animation", "Animation"]];
const PLAY_INTERVAL = 180;  // ms between frames while playing (plus the time to fetch each)
const PARTICLE_CACHE = 64;  // frames of a finished job kept in the page

/** One frame's particles (GET .../frames/N/particles): {header, xyz, values}; see docs/service.md. */
async function fetchParticles(id, frame, field) {
  const query = new URLSearchParams({ field });
  const buffer = await (await api(jobUrl(id, `/frames/${frame}/particles?${query}`), { raw: true })).arrayBuffer();
  const size = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, size)));
  return { header, xyz: new Float32Array(buffer, 4 + size, header.count * 3),
           values: new Float32Array(buffer, 4 + size + 12 * header.count, header.count) };
}

/** The particles' box (for a scene without a grid box), 3 numbers each, unused axes 0. */
function particleBox(first, dimension) {
  const lower = [Infinity, Infinity, Infinity].map((v, a) => (a < dimension ? v : 0));
  const upper = [-Infinity, -Infinity, -Infinity].map((v, a) => (a < dimension ? v : 0));
  for (let i = 0; i < first.header.count; i += 1) {  // a loop: spreading 10^5 values overflows the stack
    for (let a = 0; a < dimension; a += 1) {
      const x = first.xyz[3 * i + a];
      if (Number.isFinite(x)) { lower[a] = Math.min(lower[a], x); upper[a] = Math.max(upper[a], x); }
    }
  }
  return { lower, upper };
}

/** What the viewer frames: the grid's box (or the particles' when the scene has no grid box),
 *  three numbers each, the particle spacing and the axis drawn upwards. */
function viewerOptions(scene, listing, first) {
  const dimension = listing.dimension;
  const grid = scene.grid || {};
  let lower = [0, 0, 0], upper = [0, 0, 0];
  if (grid.lower && grid.upper) grid.lower.forEach((v, a) => { lower[a] = v; upper[a] = grid.upper[a]; });
  else ({ lower, upper } = particleBox(first, dimension));
  if (dimension === 1) upper[1] = lower[1] + 0.5 * (upper[0] - lower[0]);  // the profile's height
  const cell = Math.min(...[grid.cell_size].flat().filter(Number.isFinite), Infinity);
  const perCell = Math.max(1, ...(scene.bodies || []).map((b) => Math.max(...[b.particles_per_cell || 2].flat())));
  const spacing = Number.isFinite(cell) ? cell / perCell : Math.max(...upper.map((u, a) => u - lower[a])) / 50;
  // up: the axis gravity pulls along (y when there is none)
  const gravity = (scene.gravity || []).map(Math.abs);
  const up = dimension === 3 && gravity.length && Math.max(...gravity) > 0 ? gravity.indexOf(Math.max(...gravity)) : 1;
  return { dimension, lower, upper, spacing, up, axes: listing.axes };
}

export class ResultsPanel {
  constructor(id) {
    this.id = id;
    Object.assign(this, { record: null, scene: null, listing: null, mode: null, viewer: null, playing: false,
                          particles: new Map(), imageUrl: null, animationUrl: null, shown: null });
    this.buildControls();
    this.tabs = h("div", { class: "tabs", role: "tablist" }, RESULT_MODES.map(([mode, label]) =>
      h("button", { class: "tab", role: "tab", dataset: { mode }, onclick: () => this.setMode(mode) }, label)));
    this.stage = h("div", { class: "viewer-stage", hidden: true });
    this.colourBar = h("div", { class: "colour-bar" });
    this.image = h("img", { class: "preview-image", alt: "preview of a frame", hidden: true });
    this.animation = h("img", { class: "animation-image", alt: "animation of every frame", hidden: true });
    this.animationLinks = h("div", { class: "row animation-links", hidden: true },
      h("button", { class: "button small", onclick: () => this.saveAnimation("gif") }, "Download GIF"),
      h("button", { class: "button small", onclick: () => this.saveAnimation("mp4") }, "Download MP4"));
    this.note = h("div", { class: "placeholder" }, "No frame yet.");
    this.node = h("section", { class: "card results" },
      h("div", { class: "toolbar" }, h("h2", {}, "Results"), this.tabs),
      h("div", { class: "preview-frame" }, this.stage, this.image, this.animation, this.note),
      this.colourBar, this.animationLinks, this.controls);
  }

  /** The frame slider, its label, the play button and the field menu. */
  buildControls() {
    this.frameSlider = h("input", { type: "range", min: 0, max: 0, value: 0, step: 1, "aria-label": "frame",
                                    oninput: () => { this.stopPlaying(); this.showFrame(); } });
    this.frameLabel = h("span", { class: "frame-label" });
    this.fieldSelect = h("select", { "aria-label": "field", onchange: () => this.changeField() });
    this.play = h("button", { class: "button small play", "aria-label": "play", onclick: () => this.togglePlay() }, "▶ Play");
    this.controls = h("div", { class: "preview-controls", hidden: true },
      h("div", { class: "frame-row" }, this.play, h("label", { class: "slider" }, "Frame", this.frameSlider), this.frameLabel),
      h("label", {}, "Field", this.fieldSelect));
  }

  get frame() { return Number(this.frameSlider.value); }
  get field() { return this.fieldSelect.value; }
  get finished() { return !ACTIVE.has(this.record.status); }

  changeField() {
    this.particles.clear();
    (this.mode === "animation" ? this.showAnimation() : this.showFrame()).catch(() => {});
  }

  describeFrame(index) {
    const listed = this.listing.frames[index];
    const unit = this.listing.time_unit ? ` ${this.listing.time_unit}` : "";
    this.frameLabel.textContent = `frame ${index} / ${this.listing.frames.length - 1} (t = ${fmtNumber(listed.time, 4)}${unit})`;
  }

  /** The frames the result holds now; the slider follows the newest while it is at the end. */
  async refreshFrames() {
    const atEnd = !this.listing || this.frame >= this.listing.frames.length - 1;
    this.listing = await api(jobUrl(this.id, "/frames"));
    const count = this.listing.frames.length;
    if (!count) return false;
    if (!this.fieldSelect.options.length) {
      const preferred = this.listing.preview_field;
      this.fieldSelect.replaceChildren(...this.listing.fields.map((f) => h("option", { value: f, selected: f === preferred }, f)));
    }
    this.frameSlider.max = String(count - 1);
    if (atEnd) this.frameSlider.value = String(count - 1);
    this.controls.hidden = false;
    return true;
  }

  async showFrame() {
    if (!this.listing || !this.listing.frames.length) return;
    const index = this.frame;
    this.describeFrame(index);
    const key = `${this.mode}:${index}:${this.field}`;
    if (this.shown === key) return;
    this.shown = key;
    try {
      if (this.mode === "viewer") await this.showParticles(index);
      else if (this.mode === "image") await this.showImage(index);
      this.note.hidden = true;
    } catch (error) {
      if (error instanceof ConnectionLost) throw error;
      this.shown = null;
      this.note.hidden = false;
      this.note.textContent = `No frame: ${error.message}`;
    }
  }

  /** A frame's particles: from the page's cache once the job has finished, else fetched. */
  async particlesOf(index) {
    const key = `${index}:${this.field}`;
    const data = (this.finished && this.particles.get(key)) || await fetchParticles(this.id, index, this.field);
    if (this.finished) {
      this.particles.set(key, data);
      // keep the latest frames only (about 12 MB a frame of a million particles)
      while (this.particles.size > PARTICLE_CACHE) this.particles.delete(this.particles.keys().next().value);
    }
    return data;
  }

  async showParticles(index) {
    const data = await this.particlesOf(index);
    if (!this.viewer) {
      this.viewer = new viewer.Viewer(this.stage, viewerOptions(this.scene, this.listing, data));
      this.stage.dataset.ready = "true";
    }
    this.viewer.show(data.xyz, data.values, data.header.range);
    viewer.colourBar(this.colourBar, data.header.label, data.header.range, (x) => fmtNumber(x, 4));
    this.stage.dataset.frame = String(data.header.index);
    this.stage.dataset.field = data.header.field;
  }

  async showImage(index) {
    const query = new URLSearchParams({ frame: index, field: this.field });
    const url = URL.createObjectURL(await fetchBlob(jobUrl(this.id, `/preview.png?${query}`)));
    await loadImage(this.image, url);
    if (this.imageUrl) URL.revokeObjectURL(this.imageUrl);
    this.imageUrl = url;
    this.image.dataset.frame = String(index);
    this.image.dataset.field = this.field;
    this.image.hidden = this.mode !== "image";
  }

  async showAnimation() {
    this.stopPlaying();
    this.note.hidden = false;
    if (!this.finished) {
      this.note.textContent = "The animation is made once the job has finished.";
      return;
    }
    this.note.textContent = "Drawing every frame (the first time takes seconds to a minute)…";
    try {
      const blob = await fetchBlob(jobUrl(this.id, `/animation.gif?field=${encodeURIComponent(this.field)}`));
      if (this.animationUrl) URL.revokeObjectURL(this.animationUrl);
      this.animationUrl = URL.createObjectURL(blob);
      await loadImage(this.animation, this.animationUrl);
      this.animation.dataset.field = this.field;
      const shown = this.mode === "animation";
      this.animation.hidden = this.animationLinks.hidden = !shown;
      this.note.hidden = true;
    } catch (error) {
      if (error instanceof ConnectionLost) throw error;
      this.note.textContent = `No animation: ${error.message}`;
    }
  }

  async saveAnimation(kind) {
    const blob = await fetchBlob(jobUrl(this.id, `/animation.${kind}?field=${encodeURIComponent(this.field)}`));
    saveBlob(blob, `${(this.record && this.record.name) || this.id}.${kind}`);
  }

  setMode(mode) {
    if (mode === "viewer" && !viewer.supported()) mode = "image";
    this.mode = mode;
    this.shown = null;
    this.tabs.querySelectorAll(".tab").forEach((tab) => tab.setAttribute("aria-selected", String(tab.dataset.mode === mode)));
    this.stage.hidden = mode !== "viewer";
    this.colourBar.hidden = mode !== "viewer";
    this.image.hidden = mode !== "image" || !this.imageUrl;
    this.animation.hidden = mode !== "animation" || !this.animationUrl;
    this.animationLinks.hidden = mode !== "animation" || !this.animationUrl;
    this.controls.querySelector(".frame-row").hidden = mode === "animation";
    if (mode === "animation") this.showAnimation().catch(() => {});
    else this.showFrame().catch(() => {});
  }

  stopPlaying() {
    this.playing = false;
    this.play.textContent = "▶ Play";
    this.play.setAttribute("aria-label", "play");
  }

  async togglePlay() {
    if (this.playing) { this.stopPlaying(); return; }
    this.playing = true;
    this.play.textContent = "❚❚ Pause";
    this.play.setAttribute("aria-label", "pause");
    const count = this.listing.frames.length;
    if (this.frame >= count - 1) this.frameSlider.value = "0";
    while (this.playing) {
      await this.showFrame();
      await new Promise((resolve) => setTimeout(resolve, PLAY_INTERVAL));
      if (!this.playing) break;
      if (this.frame >= count - 1) { this.stopPlaying(); break; }
      this.frameSlider.value = String(this.frame + 1);
    }
  }

  /** The job's record and scene changed (a poll): follow the result as it grows. */
  async update(record, scene) {
    const grew = !this.record || record.step !== this.record.step || record.status !== this.record.status;
    this.record = record;
    this.scene = scene;
    if (!grew || record.status === "queued") return;
    try {
      if (!(await this.refreshFrames())) return;
    } catch (error) {
      if (error instanceof ApiError && error.status === 409) return;  // no result file yet
      throw error;
    }
    if (!this.mode) this.setMode(viewer.supported() ? "viewer" : "image");
    else if (this.mode !== "animation") await this.showFrame();
  }

  stop() {
    this.stopPlaying();
    if (this.viewer) this.viewer.destroy();
    for (const url of [this.imageUrl, this.animationUrl]) if (url) URL.revokeObjectURL(url);
  }
}

/** Show `url` in the image element; resolves once it has loaded. */
function loadImage(image, url) {
  return new Promise((resolve, reject) => { image.onload = resolve; image.onerror = reject; image.src = url; });
}
