// The "new job" form (#/new): a scene (JSON, an example, or a Karamelo input file imported by the
// service), mesh files beside it, validation with every error next to its line, submission.
import { ApiError, ConnectionLost, api } from "./api.js";
import { h, statRows } from "./dom.js";
import { fmtBytes, fmtDuration, fmtInteger } from "./format.js";
import { formatJson, jsonView } from "./json.js";

const DRAFT = "mpm.draft";  // the editor's text, kept in the tab's session storage

/** Where JSON.parse failed, as "line L, column C" (Chromium says "at position N" or "(line L column C)"). */
function parseErrorText(text, error) {
  const position = /position (\d+)/.exec(error.message);
  if (!position || /line \d+/.test(error.message)) return error.message;
  const before = text.slice(0, Number(position[1]));
  const line = before.split("\n").length;
  const column = before.length - before.lastIndexOf("\n");
  return `line ${line}, column ${column}: ${error.message}`;
}

/** A file's bytes as base64. */
async function base64(file) {
  const bytes = new Uint8Array(await file.arrayBuffer());
  let binary = "";
  for (let i = 0; i < bytes.length; i += 0x8000) binary += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(binary);
}

const isKaramelo = (file) => /\.mpm$/i.test(file.name);

/** An error heading and its items in the outcome box. */
function problems(head, items) {
  return [h("div", { class: "errors-head" }, head), h("ul", { class: "errors" }, items.map((item) => h("li", {}, item)))];
}

class NewJobForm {
  constructor(container) {
    // Mesh files beside the scene: the service never opens a path named in a scene, so a mesh
    // geometry's "file" is sent as the attached file's bytes ("data", base64) and its "format".
    this.meshes = new Map();
    this.editor = h("textarea", { class: "editor", spellcheck: "false", "aria-label": "scene JSON",
                                  placeholder: "Paste a scene (JSON) here, open a scene or a Karamelo file (.mpm), or start from an example.",
                                  oninput: () => sessionStorage.setItem(DRAFT, this.editor.value) });
    this.editor.value = sessionStorage.getItem(DRAFT) || "";
    this.examples = h("select", { class: "example-menu", "aria-label": "example", onchange: () => this.pickExample() },
      h("option", { value: "" }, "Start from an example…"));
    this.file = h("input", { type: "file", accept: ".json,application/json,.mpm", hidden: true,
                             "aria-label": "scene file", onchange: () => this.pickFile() });
    this.meshFile = h("input", { type: "file", accept: ".stl,.obj", multiple: true, hidden: true,
                                 "aria-label": "mesh file", onchange: () => this.pickMeshes() });
    this.attached = h("div", { class: "attached" });
    this.processes = h("input", { type: "number", min: 1, step: 1, placeholder: "1", class: "processes", "aria-label": "processes" });
    this.validate = h("button", { class: "button", onclick: () => this.check(false) }, "Validate");
    this.submit = h("button", { class: "button primary", onclick: () => this.check(true) }, "Submit");
    this.outcome = h("div", { class: "outcome" },
      h("div", { class: "placeholder" }, "Validate to see the particles, grid nodes, steps and memory the scene implies."));
    container.replaceChildren(h("div", { class: "columns new-job" }, this.editorCard(),
      h("section", { class: "card" }, h("h2", {}, "Validation"), this.outcome)));
    api("v1/examples").then((answer) => {
      this.examples.append(...answer.examples.map((e) =>
        h("option", { value: e.name }, e.title ? `${e.title} (${e.name})` : e.name)));
    }).catch(() => {});
  }

  editorCard() {
    return h("section", { class: "card" },
      h("div", { class: "toolbar" }, h("h1", {}, "New job"),
        h("div", { class: "row example-row" }, this.examples,
          h("button", { class: "button ghost", onclick: () => this.file.click() }, "Open file…"), this.file,
          h("button", { class: "button ghost", onclick: () => this.meshFile.click() }, "Mesh file…"), this.meshFile)),
      this.editor, this.attached,
      h("div", { class: "row end" }, h("label", { class: "inline" }, "Processes", this.processes), this.validate, this.submit));
  }

  async pickExample() {
    if (!this.examples.value) return;
    const scene = await api(`v1/examples/${encodeURIComponent(this.examples.value)}`);
    this.setText(formatJson(scene));
  }

  /** A scene file into the editor; a Karamelo file imported by the service first. */
  async pickFile() {
    const [picked] = this.file.files;
    this.file.value = "";
    if (!picked) return;
    if (isKaramelo(picked)) await this.importKaramelo(picked);
    else this.setText(await picked.text());
  }

  /** POST /v1/scenes/import/karamelo: the scene into the editor, what the import left out or noted beside it. */
  async importKaramelo(picked) {
    try {
      const body = { text: await picked.text(), name: picked.name };
      const imported = await api("v1/scenes/import/karamelo", { method: "POST", body });
      this.setText(formatJson(imported.scene));
      const lines = (title, items) => (items.length ? [h("div", { class: "import-head" }, title),
        h("ul", { class: "import-lines" }, items.map((item) =>
          h("li", {}, h("code", {}, `line ${item.line}`), " ", item.text, " — ", item.reason)))] : []);
      this.outcome.replaceChildren(h("div", { class: "valid imported" }, `Imported ${picked.name} (Karamelo).`),
        ...lines("Left out", imported.untranslated), ...lines("Translated with a difference", imported.notes));
    } catch (error) {
      if (error instanceof ConnectionLost) return;
      const details = (error instanceof ApiError && Array.isArray(error.details)) ? error.details : [];
      this.outcome.replaceChildren(...problems(`${picked.name}: ${error.message}`, details.map((d) => d.message)));
    }
  }

  async pickMeshes() {
    for (const picked of this.meshFile.files) {
      this.meshes.set(picked.name, { data: await base64(picked), format: picked.name.split(".").pop().toLowerCase() });
    }
    this.meshFile.value = "";
    this.attached.replaceChildren(...[...this.meshes.keys()].map((name) => h("span", { class: "chip" }, `Mesh: ${name}`)));
  }

  /** The scene with each mesh "file" replaced by its attached file's data; the names not attached. */
  inlineMeshes(node, missing) {
    if (Array.isArray(node)) return node.map((item) => this.inlineMeshes(item, missing));
    if (!node || typeof node !== "object") return node;
    const out = Object.fromEntries(Object.entries(node).map(([k, v]) => [k, this.inlineMeshes(v, missing)]));
    if (out.type === "mesh" && typeof out.file === "string") {
      const mesh = this.meshes.get(out.file.split(/[\\/]/).pop());
      if (!mesh) { missing.push(out.file); return out; }
      delete out.file;
      out.data = mesh.data;
      out.format = out.format || mesh.format;
    }
    return out;
  }

  setText(text) {
    this.editor.value = text;
    sessionStorage.setItem(DRAFT, text);
    this.outcome.replaceChildren();
  }

  /** The scene to send (meshes inlined), or null after saying why there is none. */
  sceneToSend() {
    let scene;
    try {
      scene = JSON.parse(this.editor.value);
    } catch (error) {
      this.outcome.replaceChildren(...problems("The scene is not valid JSON", [parseErrorText(this.editor.value, error)]));
      return null;
    }
    const missing = [];
    const sent = this.inlineMeshes(scene, missing);
    if (missing.length) {
      this.outcome.replaceChildren(...problems("Attach the mesh files the scene names (Mesh file…)",
        missing.map((name) => [h("code", {}, name), " is not attached"])));
      return null;
    }
    return { scene, sent };
  }

  async check(andSubmit) {
    const parsed = this.sceneToSend();
    if (!parsed) return;
    this.validate.disabled = this.submit.disabled = true;
    try {
      if (andSubmit) {
        const body = { scene: parsed.sent };
        if (this.processes.value) body.processes = Number(this.processes.value);
        const job = await api("v1/jobs", { method: "POST", body });
        sessionStorage.removeItem(DRAFT);
        location.hash = `#/jobs/${job.id}`;
      } else {
        this.showSummary((await api("v1/scenes/validate", { method: "POST", body: parsed.sent })).summary);
      }
    } catch (error) {
      if (error instanceof ApiError && error.status === 422 && Array.isArray(error.details)) this.showErrors(parsed.scene, error);
      else if (!(error instanceof ConnectionLost)) {
        this.outcome.replaceChildren(h("div", { class: "errors-head" }, error.message));
      }
    } finally {
      this.validate.disabled = this.submit.disabled = false;
    }
  }

  showSummary(summary) {
    const rows = [
      ["Particles", fmtInteger(summary.particles)],
      ["Grid nodes", fmtInteger(summary.grid_nodes)],
      ["Estimated steps", fmtInteger(summary.estimated_steps)],
      ["Memory", fmtBytes(summary.memory_bytes)],
      ["Estimated run time", fmtDuration(summary.estimated_run_seconds)],
    ];
    this.outcome.replaceChildren(h("div", { class: "valid" }, "✓ The scene is valid."),
      h("dl", { class: "stats summary" }, statRows(rows)));
  }

  showErrors(scene, error) {
    const byPath = new Map();
    for (const item of error.details) {
      const path = item.path || "";
      byPath.set(path, [...(byPath.get(path) || []), item.message]);
    }
    this.outcome.replaceChildren(
      h("div", { class: "errors-head" }, `${error.details.length} problem${error.details.length === 1 ? "" : "s"} in the scene`),
      h("ul", { class: "errors" }, error.details.map((item) =>
        h("li", { dataset: { path: item.path || "" } }, h("code", {}, item.path || "(scene)"), " ", item.message))),
      h("div", { class: "annotated" }, jsonView(scene, byPath)));
    const first = this.outcome.querySelector(".line.has-error");
    if (first) first.scrollIntoView({ block: "nearest" });
  }
}

export function newJobView(container) {
  new NewJobForm(container);  // nothing to poll: the form lives in the page until the route changes
}
