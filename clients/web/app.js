// The MPM dashboard: a job table, a job page and a "new job" form over the HTTP API (/v1).
// Plain JavaScript, no build step, no network access beyond the service itself.
// Routes (hash): #/jobs[?status=S], #/jobs/ID, #/sweeps, #/sweeps/ID, #/new.
"use strict";

(() => {
  const STATUSES = ["queued", "running", "succeeded", "failed", "cancelled"];
  const ACTIVE = new Set(["queued", "running"]);
  const PAGE_SIZE = 50;
  const ENERGY_SERIES = [
    ["kinetic_energy", "kinetic", "var(--kinetic)"],
    ["strain_energy", "strain", "var(--strain)"],
    ["total_energy", "total", "var(--total)"],
    // stored energy minus the work done on the bodies (gravity, loads, walls, damping, ...):
    // constant when energy is conserved; its drift from the start is the balance error
    ["energy_balance", "balance", "var(--balance)"],
  ];

  // ---------------------------------------------------------------- DOM helpers

  /** Element with attributes (on* are listeners) and children (strings become text, never HTML). */
  function h(tag, attrs = {}, ...children) {
    const svg = ["svg", "g", "path", "line", "polyline", "text", "rect", "circle", "title"].includes(tag);
    const node = svg ? document.createElementNS("http://www.w3.org/2000/svg", tag) : document.createElement(tag);
    for (const [key, value] of Object.entries(attrs)) {
      if (value === null || value === undefined || value === false) continue;
      if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
      else if (key === "dataset") Object.assign(node.dataset, value);
      else node.setAttribute(key, value === true ? "" : value);
    }
    for (const child of children.flat()) {
      if (child === null || child === undefined || child === false) continue;
      node.append(child instanceof Node ? child : String(child));
    }
    return node;
  }

  // ---------------------------------------------------------------- formatting

  function fmtNumber(x, digits = 4) {
    if (x === null || x === undefined || !Number.isFinite(x)) return "–";
    if (x === 0) return "0";
    const abs = Math.abs(x);
    if (abs >= 1e5 || abs < 1e-3) return x.toExponential(2);
    return String(Number(x.toPrecision(digits)));
  }

  function fmtInteger(x) {
    return x === null || x === undefined ? "–" : Math.round(x).toLocaleString("en-US");
  }

  function fmtDuration(seconds) {
    if (seconds === null || seconds === undefined || !Number.isFinite(seconds) || seconds < 0) return "–";
    const s = Math.round(seconds);
    const hours = Math.floor(s / 3600), minutes = Math.floor((s % 3600) / 60), secs = s % 60;
    const pad = (n) => String(n).padStart(2, "0");
    return hours ? `${hours}:${pad(minutes)}:${pad(secs)}` : `${minutes}:${pad(secs)}`;
  }

  function fmtAge(iso) {
    if (!iso) return "–";
    const seconds = (Date.now() - Date.parse(iso)) / 1000;
    if (!Number.isFinite(seconds)) return "–";
    if (seconds < 60) return `${Math.max(0, Math.floor(seconds))} s ago`;
    if (seconds < 3600) return `${Math.floor(seconds / 60)} min ago`;
    if (seconds < 86400) return `${Math.floor(seconds / 3600)} h ago`;
    return `${Math.floor(seconds / 86400)} d ago`;
  }

  function fmtBytes(bytes) {
    if (bytes === null || bytes === undefined) return "–";
    const units = ["B", "KiB", "MiB", "GiB", "TiB"];
    let value = bytes, unit = 0;
    while (value >= 1024 && unit < units.length - 1) { value /= 1024; unit += 1; }
    return `${value.toFixed(unit ? 1 : 0)} ${units[unit]}`;
  }

  /** A timestamp as "14:03:27" today, "May 2, 14:03" before. */
  function fmtTime(iso) {
    if (!iso) return "–";
    const date = new Date(iso);
    if (date.toDateString() === new Date().toDateString()) return date.toLocaleTimeString([], { hour12: false });
    return date.toLocaleString([], { month: "short", day: "numeric", hour: "2-digit", minute: "2-digit", hour12: false });
  }

  /** Wall time of a job: started to finished, or to now while it runs. */
  function wallSeconds(record) {
    if (!record.started_at) return null;
    const end = record.finished_at ? Date.parse(record.finished_at) : Date.now();
    return (end - Date.parse(record.started_at)) / 1000;
  }

  function badge(status) {
    return h("span", { class: `badge ${status}` }, status);
  }

  function progressBar(record) {
    const percent = Math.round(Math.min(1, Math.max(0, record.progress || 0)) * 1000) / 10;
    return h("div", { class: `progress ${record.status}`, role: "progressbar", "aria-valuenow": percent,
                      "aria-valuemin": 0, "aria-valuemax": 100 },
      h("div", { class: "progress-track" }, h("div", { class: "progress-fill", style: `width: ${percent}%` })),
      h("span", { class: "progress-label" }, `${percent.toFixed(1)}%`));
  }

  // ---------------------------------------------------------------- the API

  /** An error answer of the service: {"error": {"code", "message", "details"}}. */
  class ApiError extends Error {
    constructor(status, code, message, details) {
      super(message);
      this.status = status;
      this.code = code;
      this.details = details;
    }
  }

  /** The service could not be reached (or a gateway in front of it answered 502/503/504). */
  class ConnectionLost extends Error {}

  // The API token lives in this tab's session storage: gone when the tab closes, never in a URL.
  const auth = {
    get token() { return sessionStorage.getItem("mpm.token") || ""; },
    set token(value) { value ? sessionStorage.setItem("mpm.token", value) : sessionStorage.removeItem("mpm.token"); },
  };

  /** Call the API with a relative URL (the dashboard is served beside it); parses JSON unless raw. */
  async function api(path, { method = "GET", body, raw = false } = {}) {
    const headers = { Accept: "application/json" };
    if (auth.token) headers.Authorization = `Bearer ${auth.token}`;
    if (body !== undefined) headers["Content-Type"] = "application/json";
    let response;
    try {
      response = await fetch(path, { method, headers, cache: "no-store",
                                     body: body === undefined ? undefined : JSON.stringify(body) });
    } catch (error) {
      banner.connectionLost();
      throw new ConnectionLost(`cannot reach the service: ${error.message}`);
    }
    if ([502, 503, 504].includes(response.status)) {
      banner.connectionLost();
      throw new ConnectionLost(`the service answered ${response.status}`);
    }
    banner.connectionOk();
    if (!response.ok) {
      let payload = null;
      try { payload = await response.json(); } catch (_) { /* not JSON */ }
      const error = (payload && payload.error) || {};
      if (response.status === 401) banner.needToken();
      throw new ApiError(response.status, error.code || null,
                         error.message || `${method} ${path} answered ${response.status}`, error.details || null);
    }
    if (raw) return response;
    return response.status === 204 ? null : response.json();
  }

  const jobUrl = (id, tail = "") => `v1/jobs/${encodeURIComponent(id)}${tail}`;

  // ---------------------------------------------------------------- banner (connection, token)

  const banner = {
    node: document.getElementById("banner"),
    state: "ok",
    connectionLost() {
      if (this.state === "lost") return;
      this.state = "lost";
      this.show("warning", "Lost the connection to the service. Retrying…",
                h("button", { class: "button small", onclick: () => poller.current && poller.current.now() }, "Retry now"));
    },
    connectionOk() {
      if (this.state !== "lost") return;
      this.state = "ok";
      this.show("ok", "Connection restored.");
      clearTimeout(this.timer);
      this.timer = setTimeout(() => { if (this.state === "ok") this.node.hidden = true; }, 2500);
    },
    needToken() {
      if (this.state === "token") return;
      this.state = "token";
      const input = h("input", { type: "password", placeholder: "API token", "aria-label": "API token" });
      const save = (event) => {
        event.preventDefault();
        auth.token = input.value.trim();
        this.state = "ok";
        this.node.hidden = true;
        route();
      };
      this.show("warning", "This service needs an API token.", h("form", { class: "token-form", onsubmit: save },
        input, h("button", { class: "button small", type: "submit" }, "Save")));
    },
    show(kind, text, ...extra) {
      clearTimeout(this.timer);
      this.node.className = `banner ${kind}`;
      this.node.replaceChildren(h("span", {}, text), ...extra);
      this.node.hidden = false;
    },
  };

  // ---------------------------------------------------------------- polling

  /**
   * Runs `task` again and again. `task` resolves to true while something is active
   * (then it polls every `fast` ms); when nothing runs the delay doubles up to
   * `idleMax`, after an error up to `errorMax`; a hidden tab polls at most every
   * `hidden` ms and polls at once when it is shown again. `cleanup` runs on stop.
   */
  class Poller {
    constructor(task, { fast = 1000, idleMax = 15000, errorMax = 30000, hidden = 30000, cleanup = () => {} } = {}) {
      Object.assign(this, { task, fast, idleMax, errorMax, hidden, cleanup });
      this.idleDelay = 0;
      this.errorDelay = 0;
      this.onVisibility = () => { if (!document.hidden) this.now(); };
    }

    start() {
      this.stopped = false;
      document.addEventListener("visibilitychange", this.onVisibility);
      this.now();
    }

    stop() {
      this.stopped = true;
      clearTimeout(this.timer);
      document.removeEventListener("visibilitychange", this.onVisibility);
      this.cleanup();
    }

    /** Poll right away (after an action, or when the tab comes back). */
    async now() {
      if (this.stopped) return;
      if (this.inFlight) { this.again = true; return; }
      clearTimeout(this.timer);
      this.inFlight = true;
      let delay;
      try {
        const active = await this.task();
        this.errorDelay = 0;
        this.idleDelay = active ? 0 : Math.min(this.idleMax, (this.idleDelay || this.fast) * 2);
        delay = active ? this.fast : this.idleDelay;
      } catch (error) {
        if (!(error instanceof ConnectionLost)) console.error(error);
        this.errorDelay = Math.min(this.errorMax, (this.errorDelay || 500) * 2);
        delay = this.errorDelay;
      } finally {
        this.inFlight = false;
      }
      if (document.hidden) delay = Math.max(delay, this.hidden);
      if (this.again) { this.again = false; delay = 0; }
      this.delay = delay;
      document.body.dataset.pollDelay = String(delay);  // visible to tests and the curious
      if (!this.stopped) this.timer = setTimeout(() => this.now(), delay);
    }
  }

  const poller = { current: null };

  // ---------------------------------------------------------------- JSON view (scene, validation errors)

  /**
   * The document as indented lines; each line carries `data-path` in the scene's
   * error notation (`bodies[1].geometry.radius`), and `errors` (path -> messages)
   * are shown next to their line. An error whose path is not in the document
   * (a missing key) goes next to its nearest ancestor that is.
   */
  function jsonView(document_, errors = new Map()) {
    const lines = [];
    const paths = new Set();
    const indent = (depth) => "  ".repeat(depth);

    function scalar(value) {
      if (typeof value === "string") return h("span", { class: "j-str" }, JSON.stringify(value));
      if (typeof value === "number") return h("span", { class: "j-num" }, String(value));
      return h("span", { class: "j-lit" }, String(value));
    }

    function walk(value, path, depth, key, last) {
      const comma = last ? "" : ",";
      const label = key === null ? [] : [h("span", { class: "j-key" }, JSON.stringify(key)), ": "];
      paths.add(path);
      if (value !== null && typeof value === "object") {
        if (Array.isArray(value) && value.length <= 8 && value.every((v) => v === null || typeof v !== "object")) {
          const items = value.flatMap((v, i) => (i ? [", ", scalar(v)] : [scalar(v)]));
          lines.push([path, [indent(depth), ...label, "[", ...items, "]" + comma]]);  // [x, y] on one line
          return;
        }
        const entries = Array.isArray(value) ? value.map((v, i) => [i, v]) : Object.entries(value);
        const [open, close] = Array.isArray(value) ? ["[", "]"] : ["{", "}"];
        if (!entries.length) {
          lines.push([path, [indent(depth), ...label, open + close + comma]]);
          return;
        }
        lines.push([path, [indent(depth), ...label, open]]);
        entries.forEach(([k, v], i) => {
          const child = Array.isArray(value) ? `${path}[${k}]` : (path ? `${path}.${k}` : k);
          walk(v, child, depth + 1, Array.isArray(value) ? null : k, i === entries.length - 1);
        });
        lines.push([null, [indent(depth), close + comma]]);
      } else {
        lines.push([path, [indent(depth), ...label, scalar(value), comma]]);
      }
    }
    walk(document_, "", 0, null, true);

    // attach every error to its line, or to the nearest ancestor that exists
    const placed = new Map();
    for (const [path, messages] of errors) {
      let anchor = path;
      while (anchor && !paths.has(anchor)) anchor = anchor.replace(/(\.[^.[\]]+|\[\d+\])$|^[^.[\]]+$/, "");
      const items = placed.get(anchor) || [];
      for (const message of messages) items.push(anchor === path ? message : `${path}: ${message}`);
      placed.set(anchor, items);
    }

    return h("pre", { class: "json" }, lines.map(([path, parts]) => {
      const messages = path === null ? [] : placed.get(path) || [];
      return h("div", { class: messages.length ? "line has-error" : "line", dataset: path === null ? {} : { path } },
        h("span", { class: "code" }, parts),
        messages.map((message) => h("span", { class: "field-error" }, message)));
    }));
  }

  /** JSON text indented by two, with short arrays of numbers on one line (`"lower": [-0.5, -0.5]`). */
  function formatJson(value, depth = 0) {
    const pad = "  ".repeat(depth + 1), end = "  ".repeat(depth);
    if (Array.isArray(value)) {
      if (value.length <= 8 && value.every((v) => v === null || typeof v !== "object")) {
        return `[${value.map((v) => JSON.stringify(v)).join(", ")}]`;
      }
      return value.length ? `[\n${value.map((v) => pad + formatJson(v, depth + 1)).join(",\n")}\n${end}]` : "[]";
    }
    if (value !== null && typeof value === "object") {
      const entries = Object.entries(value);
      return entries.length
        ? `{\n${entries.map(([k, v]) => `${pad}${JSON.stringify(k)}: ${formatJson(v, depth + 1)}`).join(",\n")}\n${end}}`
        : "{}";
    }
    return JSON.stringify(value);
  }

  // ---------------------------------------------------------------- energy plot (SVG)

  function niceTicks(min, max, count = 5) {
    if (!(max > min)) { max = min + 1; }
    const raw = (max - min) / count;
    const magnitude = 10 ** Math.floor(Math.log10(raw));
    const step = [1, 2, 2.5, 5, 10].map((m) => m * magnitude).find((s) => s >= raw);
    const ticks = [];
    for (let t = Math.ceil(min / step) * step; t <= max + step * 1e-9; t += step) ticks.push(Number(t.toPrecision(12)));
    return ticks;
  }

  /** Line plot of the energies against time, and the energy balance's error as a number. */
  function energyPlot(series) {
    const present = ENERGY_SERIES.filter(([key]) => Array.isArray(series[key]) && series[key].length);
    const plot = linePlot(present.map(([key, label, colour]) => ({ label, colour, x: series.time || [], y: series[key] })),
                          "energy", "No energy data yet.");
    const error = series.energy_error;
    if (!Array.isArray(error) || !error.length || !plot.classList.contains("energy")) return plot;
    const last = error[error.length - 1];
    const largest = Math.max(...error.filter(Number.isFinite).map(Math.abs));
    const scale = Math.max(...["total_energy", "external_work", "boundary_work"].flatMap((key) =>
      (series[key] || []).filter(Number.isFinite).map(Math.abs)), 0);
    const share = scale > 0 ? ` (${fmtNumber(100 * last / scale, 3)} % of the largest energy)` : "";
    plot.append(h("p", { class: "balance-error" }, `Energy balance error now: ${fmtNumber(last)}${share}; `
      + `largest: ${fmtNumber(largest)}`));
    return plot;
  }

  /** Lines ({label, colour, x, y}) on shared axes, y against time; thins each to ~1500 points. */
  function linePlot(lines, yLabel, emptyText) {
    lines = lines.filter((line) => line.x.length >= 2 && line.y.length);
    if (!lines.length) return h("div", { class: "placeholder" }, emptyText);
    const thinned = lines.map((line) => {
      const stride = Math.max(1, Math.ceil(line.x.length / 1500));
      const index = [];
      for (let i = 0; i < line.x.length; i += stride) index.push(i);
      if (index[index.length - 1] !== line.x.length - 1) index.push(line.x.length - 1);
      return { ...line, index: index.filter((i) => Number.isFinite(line.y[i]) && Number.isFinite(line.x[i])) };
    });
    const values = thinned.flatMap((line) => line.index.map((i) => line.y[i]));
    const times = thinned.flatMap((line) => line.index.map((i) => line.x[i]));
    let [ymin, ymax] = [Math.min(0, ...values), Math.max(...values)];
    if (!(ymax > ymin)) ymax = ymin + 1;
    const yTicks = niceTicks(ymin, ymax);
    ymin = Math.min(ymin, yTicks[0]);
    ymax = Math.max(ymax, yTicks[yTicks.length - 1]);
    const [xmin, xmax] = [Math.min(...times), Math.max(...times)];

    const W = 560, H = 300, left = 64, right = 16, top = 16, bottom = 40;
    const x = (t) => left + ((t - xmin) / (xmax - xmin || 1)) * (W - left - right);
    const y = (e) => H - bottom - ((e - ymin) / (ymax - ymin)) * (H - top - bottom);

    const grid = yTicks.map((t) => h("g", { class: "tick" },
      h("line", { x1: left, x2: W - right, y1: y(t), y2: y(t) }),
      h("text", { x: left - 8, y: y(t) + 4, "text-anchor": "end" }, fmtNumber(t, 3))));
    const xTicks = niceTicks(xmin, xmax, 6).filter((t) => t >= xmin && t <= xmax).map((t) => h("g", { class: "tick x" },
      h("line", { x1: x(t), x2: x(t), y1: H - bottom, y2: H - bottom + 5 }),
      h("text", { x: x(t), y: H - bottom + 19, "text-anchor": "middle" }, fmtNumber(t, 3))));
    const polylines = thinned.map((line) => {
      const points = line.index.map((i) => `${x(line.x[i]).toFixed(1)},${y(line.y[i]).toFixed(1)}`).join(" ");
      return h("polyline", { class: "series", points, style: `stroke: ${line.colour}`, dataset: { label: line.label } },
        h("title", {}, line.label));
    });

    return h("figure", { class: "energy" },
      h("svg", { class: "energy-plot", viewBox: `0 0 ${W} ${H}`, role: "img", "aria-label": `${yLabel} against time` },
        grid, xTicks,
        h("line", { class: "axis", x1: left, x2: W - right, y1: H - bottom, y2: H - bottom }),
        h("line", { class: "axis", x1: left, x2: left, y1: top, y2: H - bottom }),
        h("text", { class: "axis-label", x: (left + W - right) / 2, y: H - 4, "text-anchor": "middle" }, "time"),
        h("text", { class: "axis-label", x: 14, y: (top + H - bottom) / 2, "text-anchor": "middle",
                    transform: `rotate(-90 14 ${(top + H - bottom) / 2})` }, yLabel),
        polylines),
      h("figcaption", { class: "legend" }, thinned.map((line) =>
        h("span", { class: "legend-item" }, h("i", { style: `background: ${line.colour}` }), line.label))));
  }

  // ---------------------------------------------------------------- view: job list

  function jobsView(container, params) {
    const status = STATUSES.includes(params.get("status")) ? params.get("status") : "";
    let pages = 1;
    const body = h("tbody");
    const empty = h("div", { class: "placeholder", hidden: true });
    const more = h("button", { class: "button ghost", hidden: true, onclick: () => { pages += 1; poller.current.now(); } },
      "Show older jobs");
    const filters = h("div", { class: "filters", role: "group", "aria-label": "status filter" },
      ["", ...STATUSES].map((s) => h("a", {
        class: s === status ? "chip active" : "chip", href: s ? `#/jobs?status=${s}` : "#/jobs",
        dataset: { status: s || "all" },
      }, s || "all")));

    container.replaceChildren(h("section", { class: "card" },
      h("div", { class: "toolbar" }, h("h1", {}, "Jobs"), filters),
      h("div", { class: "table-wrap" }, h("table", { class: "jobs" },
        h("thead", {}, h("tr", {}, ["Name", "Status", "Progress", "Sim time", "Steps/s", "ETA", "Age"]
          .map((title) => h("th", {}, title)))),
        body)),
      empty, more));

    async function load() {
      const jobs = [];
      let cursor = null;
      for (let page = 0; page < pages; page += 1) {
        const query = new URLSearchParams({ limit: PAGE_SIZE });
        if (status) query.set("status", status);
        if (cursor) query.set("cursor", cursor);
        const answer = await api(`v1/jobs?${query}`);
        jobs.push(...answer.jobs);
        cursor = answer.next_cursor;
        if (!cursor) break;
      }
      body.replaceChildren(...jobs.map(jobRow));
      empty.hidden = jobs.length > 0;
      empty.replaceChildren(status ? `No ${status} jobs.` : "No jobs yet. ",
                            status ? "" : h("a", { href: "#/new" }, "Submit one."));
      more.hidden = !cursor;
      return jobs.some((job) => ACTIVE.has(job.status));
    }
    return new Poller(load);
  }

  function jobRow(job) {
    const open = () => { location.hash = `#/jobs/${job.id}`; };
    const end = job.end_time ? ` / ${fmtNumber(job.end_time)}` : "";
    return h("tr", { class: "job-row", dataset: { id: job.id, status: job.status }, onclick: open },
      h("td", { class: "name" }, h("a", { href: `#/jobs/${job.id}`, title: job.name || "" }, job.name || "(unnamed)"),
        h("div", { class: "id" }, job.id.slice(0, 8))),
      h("td", {}, badge(job.status)),
      h("td", { class: "progress-cell" }, progressBar(job)),
      h("td", { class: "num" }, `${fmtNumber(job.sim_time)}${end}`),
      h("td", { class: "num" }, job.status === "running" ? fmtInteger(job.steps_per_second) : "–"),
      h("td", { class: "num" }, job.status === "running" ? fmtDuration(job.eta_seconds) : "–"),
      h("td", { class: "age", title: fmtTime(job.created_at) }, fmtAge(job.created_at)));
  }

  // ---------------------------------------------------------------- view: one job

  // ---------------------------------------------------------------- results: viewer, image, animation

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

  /** What the viewer frames: the grid's box (or the particles' when the scene has no grid box),
   *  three numbers each, the particle spacing and the axis drawn upwards. */
  function viewerOptions(scene, listing, first) {
    const dimension = listing.dimension;
    const grid = scene.grid || {};
    let lower = [0, 0, 0], upper = [0, 0, 0];
    if (grid.lower && grid.upper) {
      grid.lower.forEach((v, a) => { lower[a] = v; upper[a] = grid.upper[a]; });
    } else {
      lower = [Infinity, Infinity, Infinity].map((v, a) => (a < dimension ? v : 0));
      upper = [-Infinity, -Infinity, -Infinity].map((v, a) => (a < dimension ? v : 0));
      for (let i = 0; i < first.header.count; i += 1) {  // a loop: spreading 10^5 values overflows the stack
        for (let a = 0; a < dimension; a += 1) {
          const x = first.xyz[3 * i + a];
          if (Number.isFinite(x)) { lower[a] = Math.min(lower[a], x); upper[a] = Math.max(upper[a], x); }
        }
      }
    }
    if (dimension === 1) upper[1] = lower[1] + 0.5 * (upper[0] - lower[0]);  // the profile's height
    const cell = Math.min(...[grid.cell_size].flat().filter(Number.isFinite), Infinity);
    const perCell = Math.max(1, ...(scene.bodies || []).map((b) => Math.max(...[b.particles_per_cell || 2].flat())));
    const spacing = Number.isFinite(cell) ? cell / perCell : Math.max(...upper.map((u, a) => u - lower[a])) / 50;
    // up: the axis gravity pulls along (y when there is none)
    const gravity = (scene.gravity || []).map(Math.abs);
    const up = dimension === 3 && gravity.length && Math.max(...gravity) > 0 ? gravity.indexOf(Math.max(...gravity)) : 1;
    return { dimension, lower, upper, spacing, up, axes: listing.axes };
  }

  /** The job page's results card: a WebGL viewer, the PNG image or the animation of the frames
   *  the result holds (the count and times come from the result, GET .../frames). */
  function resultsPanel(id) {
    const state = { record: null, scene: null, listing: null, mode: null, viewer: null, playing: false,
                    particles: new Map(), imageUrl: null, animationUrl: null, shown: null };
    const tabs = h("div", { class: "tabs", role: "tablist" }, RESULT_MODES.map(([mode, label]) =>
      h("button", { class: "tab", role: "tab", dataset: { mode }, onclick: () => setMode(mode) }, label)));
    const stage = h("div", { class: "viewer-stage", hidden: true });
    const colourBar = h("div", { class: "colour-bar" });
    const image = h("img", { class: "preview-image", alt: "preview of a frame", hidden: true });
    const animation = h("img", { class: "animation-image", alt: "animation of every frame", hidden: true });
    const animationLinks = h("div", { class: "row animation-links", hidden: true },
      h("button", { class: "button small", onclick: () => saveAnimation("gif") }, "Download GIF"),
      h("button", { class: "button small", onclick: () => saveAnimation("mp4") }, "Download MP4"));
    const note = h("div", { class: "placeholder" }, "No frame yet.");
    const frameSlider = h("input", { type: "range", min: 0, max: 0, value: 0, step: 1, "aria-label": "frame",
                                    oninput: () => { stopPlaying(); showFrame(); } });
    const frameLabel = h("span", { class: "frame-label" });
    const fieldSelect = h("select", { "aria-label": "field", onchange: changeField });
    const play = h("button", { class: "button small play", "aria-label": "play", onclick: togglePlay }, "▶ Play");
    const controls = h("div", { class: "preview-controls", hidden: true },
      h("div", { class: "frame-row" }, play, h("label", { class: "slider" }, "Frame", frameSlider), frameLabel),
      h("label", {}, "Field", fieldSelect));
    const node = h("section", { class: "card results" },
      h("div", { class: "toolbar" }, h("h2", {}, "Results"), tabs),
      h("div", { class: "preview-frame" }, stage, image, animation, note), colourBar, animationLinks, controls);

    const frame = () => Number(frameSlider.value);

    function changeField() {
      state.particles.clear();
      (state.mode === "animation" ? showAnimation() : showFrame()).catch(() => {});
    }
    const field = () => fieldSelect.value;

    function describeFrame(index) {
      const listed = state.listing.frames[index];
      const unit = state.listing.time_unit ? ` ${state.listing.time_unit}` : "";
      frameLabel.textContent = `frame ${index} / ${state.listing.frames.length - 1} (t = ${fmtNumber(listed.time, 4)}${unit})`;
    }

    /** The frames the result holds now; the slider follows the newest while it is at the end. */
    async function refreshFrames() {
      const atEnd = !state.listing || frame() >= state.listing.frames.length - 1;
      state.listing = await api(jobUrl(id, "/frames"));
      const count = state.listing.frames.length;
      if (!count) return false;
      if (!fieldSelect.options.length) {
        const preferred = state.listing.preview_field;
        fieldSelect.replaceChildren(...state.listing.fields.map((f) => h("option", { value: f, selected: f === preferred }, f)));
      }
      frameSlider.max = String(count - 1);
      if (atEnd) frameSlider.value = String(count - 1);
      controls.hidden = false;
      return true;
    }

    async function showFrame() {
      if (!state.listing || !state.listing.frames.length) return;
      const index = frame();
      describeFrame(index);
      const key = `${state.mode}:${index}:${field()}`;
      if (state.shown === key) return;
      state.shown = key;
      try {
        if (state.mode === "viewer") await showParticles(index);
        else if (state.mode === "image") await showImage(index);
        note.hidden = true;
      } catch (error) {
        if (error instanceof ConnectionLost) throw error;
        state.shown = null;
        note.hidden = false;
        note.textContent = `No frame: ${error.message}`;
      }
    }

    async function showParticles(index) {
      const key = `${index}:${field()}`;
      const finished = !ACTIVE.has(state.record.status);
      const data = (finished && state.particles.get(key)) || await fetchParticles(id, index, field());
      if (finished) {
        state.particles.set(key, data);
        // keep the latest frames only (about 12 MB a frame of a million particles)
        while (state.particles.size > PARTICLE_CACHE) state.particles.delete(state.particles.keys().next().value);
      }
      if (!state.viewer) {
        state.viewer = window.MpmViewer.create(stage, viewerOptions(state.scene, state.listing, data));
        stage.dataset.ready = "true";
      }
      state.viewer.show(data.xyz, data.values, data.header.range);
      window.MpmViewer.colourBar(colourBar, data.header.label, data.header.range, (x) => fmtNumber(x, 4));
      stage.dataset.frame = String(data.header.index);
      stage.dataset.field = data.header.field;
    }

    async function showImage(index) {
      const query = new URLSearchParams({ frame: index, field: field() });
      const url = URL.createObjectURL(await (await api(jobUrl(id, `/preview.png?${query}`), { raw: true })).blob());
      await new Promise((resolve, reject) => { image.onload = resolve; image.onerror = reject; image.src = url; });
      if (state.imageUrl) URL.revokeObjectURL(state.imageUrl);
      state.imageUrl = url;
      image.dataset.frame = String(index);
      image.dataset.field = field();
      image.hidden = state.mode !== "image";
    }

    async function showAnimation() {
      stopPlaying();
      if (ACTIVE.has(state.record.status)) {
        note.hidden = false;
        note.textContent = "The animation is made once the job has finished.";
        return;
      }
      note.hidden = false;
      note.textContent = "Drawing every frame (the first time takes seconds to a minute)…";
      try {
        const blob = await (await api(jobUrl(id, `/animation.gif?field=${encodeURIComponent(field())}`), { raw: true })).blob();
        if (state.animationUrl) URL.revokeObjectURL(state.animationUrl);
        state.animationUrl = URL.createObjectURL(blob);
        await new Promise((resolve, reject) => {
          animation.onload = resolve; animation.onerror = reject; animation.src = state.animationUrl;
        });
        animation.dataset.field = field();
        const shown = state.mode === "animation";
        animation.hidden = animationLinks.hidden = !shown;
        note.hidden = true;
      } catch (error) {
        if (error instanceof ConnectionLost) throw error;
        note.textContent = `No animation: ${error.message}`;
      }
    }

    async function saveAnimation(kind) {
      const blob = await (await api(jobUrl(id, `/animation.${kind}?field=${encodeURIComponent(field())}`), { raw: true })).blob();
      const url = URL.createObjectURL(blob);
      const link = h("a", { href: url, download: `${(state.record && state.record.name) || id}.${kind}`, hidden: true });
      document.body.append(link);
      link.click();
      link.remove();
      setTimeout(() => URL.revokeObjectURL(url), 10000);
    }

    function setMode(mode) {
      if (mode === "viewer" && !window.MpmViewer.supported()) mode = "image";
      state.mode = mode;
      state.shown = null;
      tabs.querySelectorAll(".tab").forEach((tab) => tab.setAttribute("aria-selected", String(tab.dataset.mode === mode)));
      stage.hidden = mode !== "viewer";
      colourBar.hidden = mode !== "viewer";
      image.hidden = mode !== "image" || !state.imageUrl;
      animation.hidden = mode !== "animation" || !state.animationUrl;
      animationLinks.hidden = mode !== "animation" || !state.animationUrl;
      controls.querySelector(".frame-row").hidden = mode === "animation";
      if (mode === "animation") showAnimation().catch(() => {});
      else showFrame().catch(() => {});
    }

    function stopPlaying() {
      state.playing = false;
      play.textContent = "▶ Play";
      play.setAttribute("aria-label", "play");
    }

    async function togglePlay() {
      if (state.playing) { stopPlaying(); return; }
      state.playing = true;
      play.textContent = "❚❚ Pause";
      play.setAttribute("aria-label", "pause");
      const count = state.listing.frames.length;
      if (frame() >= count - 1) frameSlider.value = "0";
      while (state.playing) {
        await showFrame();
        await new Promise((resolve) => setTimeout(resolve, PLAY_INTERVAL));
        if (!state.playing) break;
        if (frame() >= count - 1) { stopPlaying(); break; }
        frameSlider.value = String(frame() + 1);
      }
    }

    /** The job's record and scene changed (a poll): follow the result as it grows. */
    async function update(record, scene) {
      const grew = !state.record || record.step !== state.record.step || record.status !== state.record.status;
      state.record = record;
      state.scene = scene;
      if (!grew || record.status === "queued") return;
      try {
        if (!(await refreshFrames())) return;
      } catch (error) {
        if (error instanceof ApiError && error.status === 409) return;  // no result file yet
        throw error;
      }
      if (!state.mode) setMode(window.MpmViewer.supported() ? "viewer" : "image");
      else if (state.mode !== "animation") await showFrame();
    }

    function stop() {
      stopPlaying();
      if (state.viewer) state.viewer.destroy();
      for (const url of [state.imageUrl, state.animationUrl]) if (url) URL.revokeObjectURL(url);
    }

    return { node, update, stop };
  }

  function jobView(container, id) {
    let record = null;
    let scene = null;
    let lastSeriesAt = 0;
    let finishedShown = false;
    const results = resultsPanel(id);

    const title = h("h1", {}, "Job");
    const status = h("span");
    const stats = h("dl", { class: "stats" });
    const progress = h("div");
    const errorBox = h("div", { class: "diagnostic", hidden: true });
    const cancel = h("button", { class: "button danger", onclick: doCancel }, "Cancel");
    const download = h("button", { class: "button", onclick: doDownload }, "Download HDF5");
    const remove = h("button", { class: "button ghost danger", onclick: doDelete }, "Delete");
    const plot = h("div", { class: "plot" }, h("div", { class: "placeholder" }, "No energy data yet."));
    const energyNow = h("dl", { class: "stats energies" });
    const sceneBox = h("div", { class: "scene" }, h("div", { class: "placeholder" }, "Loading…"));
    const logBox = h("pre", { class: "log", "aria-label": "solver log" });
    const logNote = h("div", { class: "placeholder" }, "No log lines yet.");
    let logLine = 0;

    container.replaceChildren(
      h("a", { class: "back", href: "#/jobs" }, "← All jobs"),
      h("section", { class: "card job-head" },
        h("div", { class: "job-title" }, h("div", {}, h("div", { class: "title-line" }, title, status),
          h("code", { class: "id" }, id))),
        h("div", { class: "actions" }, cancel, download, remove),
        progress, stats, errorBox),
      h("div", { class: "columns" },
        results.node,
        h("section", { class: "card" }, h("h2", {}, "Energy"), plot, energyNow)),
      h("section", { class: "card" }, h("details", { open: true }, h("summary", {}, h("h2", {}, "Scene")), sceneBox)),
      h("section", { class: "card" }, h("details", { open: true }, h("summary", {}, h("h2", {}, "Solver log")),
        logNote, logBox)));

    /** The log lines written since the last read (GET .../log?since=N), appended. */
    async function loadLog() {
      const answer = await api(jobUrl(id, `/log?since=${logLine}`), { raw: true });
      const text = await answer.text();
      logLine = Number(answer.headers.get("X-MPM-Next-Line") || logLine);
      if (text) logBox.append(text);
      logNote.hidden = logBox.textContent.length > 0;
    }

    function renderRecord() {
      title.textContent = record.name || "(unnamed)";
      document.title = `${record.name || id} · MPM`;
      status.replaceChildren(badge(record.status));
      progress.replaceChildren(progressBar(record));
      const summary = record.summary || {};
      const running = record.status === "running";
      const rows = [
        ["Step", fmtInteger(record.step)],
        ["Sim time", `${fmtNumber(record.sim_time)}${record.end_time ? ` / ${fmtNumber(record.end_time)}` : ""}`],
        ["Stage", running || record.status === "queued" ? record.stage || "–" : "–"],
        ["Steps/s", running ? fmtInteger(record.steps_per_second) : "–"],
        ["ETA", running ? fmtDuration(record.eta_seconds) : "–"],
        ["Particles", fmtInteger(summary.particles)],
        ["Grid nodes", fmtInteger(summary.grid_nodes)],
        ["Started", fmtTime(record.started_at)],
        ["Wall time", fmtDuration(wallSeconds(record))],
      ];
      stats.replaceChildren(...rows.map(([k, v]) => h("div", {}, h("dt", {}, k), h("dd", {}, v))));
      const energies = record.energies || {};
      energyNow.replaceChildren(...ENERGY_SERIES.map(([, label, colour]) => h("div", {},
        h("dt", {}, h("i", { class: "swatch", style: `background: ${colour}` }), `${label} now`),
        h("dd", {}, fmtNumber(energies[label])))),
        h("div", {}, h("dt", {}, "balance error now"), h("dd", {}, fmtNumber(energies.error))));
      errorBox.hidden = !record.error;
      errorBox.replaceChildren(h("strong", {}, "Diagnostic"), h("pre", {}, record.error || ""));
      cancel.disabled = !ACTIVE.has(record.status);
      download.disabled = ACTIVE.has(record.status);
      remove.disabled = ACTIVE.has(record.status);
    }

    async function loadSeries() {
      lastSeriesAt = Date.now();
      try {
        plot.replaceChildren(energyPlot(await api(jobUrl(id, "/series"))));
      } catch (error) {
        if (error instanceof ConnectionLost) throw error;
        if (!(error instanceof ApiError && error.status === 409)) {
          plot.replaceChildren(h("div", { class: "placeholder" }, `No energy data: ${error.message}`));
        }
      }
    }

    async function load() {
      try {
        record = await api(jobUrl(id));
      } catch (error) {
        if (error instanceof ApiError && error.status === 404) {
          container.replaceChildren(h("section", { class: "card" }, h("h1", {}, "No such job"),
            h("p", {}, "It may have been deleted. "), h("a", { href: "#/jobs" }, "Back to all jobs")));
          poller.current && poller.current.stop();
          return false;
        }
        throw error;
      }
      renderRecord();
      if (scene === null) {
        scene = await api(jobUrl(id, "/scene"));
        sceneBox.replaceChildren(jsonView(scene));
      }
      await results.update(record, scene);
      if (record.status === "running" && Date.now() - lastSeriesAt > 4000) await loadSeries();
      if (record.status === "running") await loadLog();
      if (!ACTIVE.has(record.status) && !finishedShown) {
        finishedShown = true;
        await loadSeries();
        await loadLog();
      }
      return ACTIVE.has(record.status);
    }

    async function doCancel() {
      cancel.disabled = true;
      try {
        await api(jobUrl(id, "/cancel"), { method: "POST" });
      } catch (error) {
        if (!(error instanceof ConnectionLost)) alert(`Could not cancel: ${error.message}`);
      }
      poller.current.now();
    }

    async function doDownload() {
      download.disabled = true;
      try {
        const blob = await (await api(jobUrl(id, "/result.h5"), { raw: true })).blob();
        const url = URL.createObjectURL(blob);
        const link = h("a", { href: url, download: `${record.name || id}.h5`, hidden: true });
        document.body.append(link);
        link.click();
        link.remove();
        setTimeout(() => URL.revokeObjectURL(url), 10000);
      } catch (error) {
        if (!(error instanceof ConnectionLost)) alert(`Could not download: ${error.message}`);
      } finally {
        download.disabled = ACTIVE.has(record.status);
      }
    }

    async function doDelete() {
      if (!confirm(`Delete job "${record.name || id}" and its files?`)) return;
      try {
        await api(jobUrl(id), { method: "DELETE" });
        location.hash = "#/jobs";
      } catch (error) {
        if (!(error instanceof ConnectionLost)) alert(`Could not delete: ${error.message}`);
      }
    }

    return new Poller(load, { cleanup: () => results.stop() });
  }

  // ---------------------------------------------------------------- view: new job

  /** Where JSON.parse failed, as "line L, column C" (Chromium says "at position N" or "(line L column C)"). */
  function parseErrorText(text, error) {
    const position = /position (\d+)/.exec(error.message);
    if (!position || /line \d+/.test(error.message)) return error.message;
    const before = text.slice(0, Number(position[1]));
    const line = before.split("\n").length;
    const column = before.length - before.lastIndexOf("\n");
    return `line ${line}, column ${column}: ${error.message}`;
  }

  function newJobView(container) {
    const editor = h("textarea", { class: "editor", spellcheck: "false", "aria-label": "scene JSON",
                                   placeholder: "Paste a scene (JSON) here, or start from an example.",
                                   oninput: () => sessionStorage.setItem("mpm.draft", editor.value) });
    editor.value = sessionStorage.getItem("mpm.draft") || "";
    const examples = h("select", { class: "example-menu", "aria-label": "example", onchange: pickExample },
      h("option", { value: "" }, "Start from an example…"));
    const file = h("input", { type: "file", accept: ".json,application/json", hidden: true, onchange: pickFile });
    // Mesh files beside the scene: the service never opens a path named in a scene, so a mesh
    // geometry's "file" is sent as the attached file's bytes ("data", base64) and its "format".
    const meshes = new Map();
    const meshFile = h("input", { type: "file", accept: ".stl,.obj", multiple: true, hidden: true,
                                  "aria-label": "mesh file", onchange: pickMeshes });
    const attached = h("div", { class: "attached" });
    const processes = h("input", { type: "number", min: 1, step: 1, placeholder: "1", class: "processes", "aria-label": "processes" });
    const validate = h("button", { class: "button", onclick: () => check(false) }, "Validate");
    const submit = h("button", { class: "button primary", onclick: () => check(true) }, "Submit");
    const outcome = h("div", { class: "outcome" },
      h("div", { class: "placeholder" }, "Validate to see the particles, grid nodes, steps and memory the scene implies."));

    container.replaceChildren(h("div", { class: "columns new-job" },
      h("section", { class: "card" },
        h("div", { class: "toolbar" }, h("h1", {}, "New job"),
          h("div", { class: "row example-row" }, examples,
            h("button", { class: "button ghost", onclick: () => file.click() }, "Open file…"), file,
            h("button", { class: "button ghost", onclick: () => meshFile.click() }, "Mesh file…"), meshFile)),
        editor, attached,
        h("div", { class: "row end" }, h("label", { class: "inline" }, "Processes", processes), validate, submit)),
      h("section", { class: "card" }, h("h2", {}, "Validation"), outcome)));

    api("v1/examples").then((answer) => {
      examples.append(...answer.examples.map((e) =>
        h("option", { value: e.name }, e.title ? `${e.title} (${e.name})` : e.name)));
    }).catch(() => {});

    async function pickExample() {
      if (!examples.value) return;
      const scene = await api(`v1/examples/${encodeURIComponent(examples.value)}`);
      setText(formatJson(scene));
    }

    async function pickFile() {
      if (file.files.length) setText(await file.files[0].text());
      file.value = "";
    }

    async function pickMeshes() {
      for (const picked of meshFile.files) {
        const bytes = new Uint8Array(await picked.arrayBuffer());
        let binary = "";
        for (let i = 0; i < bytes.length; i += 0x8000) binary += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
        meshes.set(picked.name, { data: btoa(binary), format: picked.name.split(".").pop().toLowerCase() });
      }
      meshFile.value = "";
      attached.replaceChildren(...[...meshes.keys()].map((name) => h("span", { class: "chip" }, `Mesh: ${name}`)));
    }

    /** The scene with each mesh "file" replaced by its attached file's data; the names not attached. */
    function inlineMeshes(node, missing) {
      if (Array.isArray(node)) return node.map((item) => inlineMeshes(item, missing));
      if (!node || typeof node !== "object") return node;
      const out = Object.fromEntries(Object.entries(node).map(([k, v]) => [k, inlineMeshes(v, missing)]));
      if (out.type === "mesh" && typeof out.file === "string") {
        const mesh = meshes.get(out.file.split(/[\\/]/).pop());
        if (!mesh) { missing.push(out.file); return out; }
        delete out.file;
        out.data = mesh.data;
        out.format = out.format || mesh.format;
      }
      return out;
    }

    function setText(text) {
      editor.value = text;
      sessionStorage.setItem("mpm.draft", text);
      outcome.replaceChildren();
    }

    async function check(andSubmit) {
      let scene;
      try {
        scene = JSON.parse(editor.value);
      } catch (error) {
        outcome.replaceChildren(h("div", { class: "errors-head" }, "The scene is not valid JSON"),
          h("ul", { class: "errors" }, h("li", {}, parseErrorText(editor.value, error))));
        return;
      }
      const missing = [];
      const sent = inlineMeshes(scene, missing);
      if (missing.length) {
        outcome.replaceChildren(h("div", { class: "errors-head" }, "Attach the mesh files the scene names (Mesh file…)"),
          h("ul", { class: "errors" }, missing.map((name) => h("li", {}, h("code", {}, name), " is not attached"))));
        return;
      }
      validate.disabled = submit.disabled = true;
      try {
        if (andSubmit) {
          const body = { scene: sent };
          if (processes.value) body.processes = Number(processes.value);
          const job = await api("v1/jobs", { method: "POST", body });
          sessionStorage.removeItem("mpm.draft");
          location.hash = `#/jobs/${job.id}`;
        } else {
          showSummary((await api("v1/scenes/validate", { method: "POST", body: sent })).summary);
        }
      } catch (error) {
        if (error instanceof ApiError && error.status === 422 && Array.isArray(error.details)) showErrors(scene, error);
        else if (!(error instanceof ConnectionLost)) {
          outcome.replaceChildren(h("div", { class: "errors-head" }, error.message));
        }
      } finally {
        validate.disabled = submit.disabled = false;
      }
    }

    function showSummary(summary) {
      const rows = [
        ["Particles", fmtInteger(summary.particles)],
        ["Grid nodes", fmtInteger(summary.grid_nodes)],
        ["Estimated steps", fmtInteger(summary.estimated_steps)],
        ["Memory", fmtBytes(summary.memory_bytes)],
        ["Estimated run time", fmtDuration(summary.estimated_run_seconds)],
      ];
      outcome.replaceChildren(h("div", { class: "valid" }, "✓ The scene is valid."),
        h("dl", { class: "stats summary" }, rows.map(([k, v]) => h("div", {}, h("dt", {}, k), h("dd", {}, v)))));
    }

    function showErrors(scene, error) {
      const byPath = new Map();
      for (const item of error.details) {
        const path = item.path || "";
        byPath.set(path, [...(byPath.get(path) || []), item.message]);
      }
      outcome.replaceChildren(
        h("div", { class: "errors-head" }, `${error.details.length} problem${error.details.length === 1 ? "" : "s"} in the scene`),
        h("ul", { class: "errors" }, error.details.map((item) =>
          h("li", { dataset: { path: item.path || "" } }, h("code", {}, item.path || "(scene)"), " ", item.message))),
        h("div", { class: "annotated" }, jsonView(scene, byPath)));
      const first = outcome.querySelector(".line.has-error");
      if (first) first.scrollIntoView({ block: "nearest" });
    }
  }

  // ---------------------------------------------------------------- routing

  // ---------------------------------------------------------------- views: sweeps

  const sweepUrl = (id, tail = "") => `v1/sweeps/${encodeURIComponent(id)}${tail}`;
  const LINE_COLOURS = ["#2563eb", "#dc2626", "#059669", "#d97706", "#7c3aed", "#0891b2", "#db2777", "#65a30d"];
  const showValues = (parameters) => Object.entries(parameters).map(([p, v]) => `${p} = ${JSON.stringify(v)}`).join(", ");

  function sweepsView(container) {
    const body = h("tbody");
    const empty = h("div", { class: "placeholder", hidden: true }, "No sweeps yet (POST /v1/sweeps, mpm sweep).");
    container.replaceChildren(h("section", { class: "card" }, h("div", { class: "toolbar" }, h("h1", {}, "Sweeps")),
      h("div", { class: "table-wrap" }, h("table", { class: "sweeps" },
        h("thead", {}, h("tr", {}, ["Name", "Status", "Jobs", "Progress", "Parameters", "Age"].map((t) => h("th", {}, t)))),
        body)), empty));
    async function load() {
      const { sweeps } = await api("v1/sweeps");
      body.replaceChildren(...sweeps.map((sweep) => h("tr", { class: "sweep-row", dataset: { id: sweep.id },
        onclick: () => { location.hash = `#/sweeps/${sweep.id}`; } },
        h("td", { class: "name" }, h("a", { href: `#/sweeps/${sweep.id}` }, sweep.name || "(unnamed)"),
          h("div", { class: "id" }, sweep.id.slice(0, 8))),
        h("td", {}, badge(sweep.status)),
        h("td", { class: "num" }, `${sweep.jobs.length - sweep.counts.queued - sweep.counts.running} / ${sweep.jobs.length}`),
        h("td", { class: "progress-cell" }, progressBar({ progress: sweep.progress, status: sweep.status })),
        h("td", {}, Object.keys(sweep.parameters).join(", ")),
        h("td", { class: "age" }, fmtAge(sweep.created_at)))));
      empty.hidden = sweeps.length > 0;
      return sweeps.some((sweep) => sweep.status !== "finished");
    }
    return new Poller(load);
  }

  /** A sweep: its jobs side by side (parameters, status, energies) and their total energies in one plot. */
  function sweepView(container, id) {
    const title = h("h1", {}, "Sweep");
    const head = h("div");
    const rows = h("tbody");
    const headRow = h("tr");
    const plot = h("div", { class: "plot" }, h("div", { class: "placeholder" }, "No energy data yet."));
    const series = new Map();   // job id -> its series, once the job has finished
    const cancel = h("button", { class: "button danger", onclick: async () => {
      cancel.disabled = true; await api(sweepUrl(id, "/cancel"), { method: "POST" }); poller.current.now(); } }, "Cancel sweep");
    container.replaceChildren(
      h("a", { class: "back", href: "#/sweeps" }, "← All sweeps"),
      h("section", { class: "card job-head" }, h("div", { class: "title-line" }, title),
        h("code", { class: "id" }, id), h("div", { class: "actions" }, cancel), head),
      h("section", { class: "card" }, h("h2", {}, "Jobs"), h("div", { class: "table-wrap" },
        h("table", { class: "sweep-jobs" }, h("thead", {}, headRow), rows))),
      h("section", { class: "card" }, h("h2", {}, "Total energy of each job"), plot));

    async function load() {
      let sweep;
      try {
        sweep = await api(sweepUrl(id));
      } catch (error) {
        if (error instanceof ApiError && error.status === 404) {
          container.replaceChildren(h("section", { class: "card" }, h("h1", {}, "No such sweep"),
            h("a", { href: "#/sweeps" }, "Back to all sweeps")));
          return false;
        }
        throw error;
      }
      const pointers = Object.keys(sweep.parameters);
      title.textContent = sweep.name || "(unnamed sweep)";
      document.title = `${sweep.name || id} · MPM`;
      head.replaceChildren(badge(sweep.status), progressBar({ progress: sweep.progress, status: sweep.status }),
        h("span", { class: "counts" }, STATUSES.map((s) => `${sweep.counts[s]} ${s}`).join(" · ")));
      cancel.disabled = sweep.status === "finished";
      headRow.replaceChildren(...["Job", ...pointers, "Status", "Progress", "Kinetic", "Strain", "Total"].map((t) => h("th", {}, t)));
      rows.replaceChildren(...sweep.jobs.map((job, k) => h("tr", { class: "sweep-job", dataset: { id: job.id, status: job.status } },
        h("td", {}, h("i", { class: "swatch", style: `background: ${LINE_COLOURS[k % LINE_COLOURS.length]}` }),
          h("a", { href: `#/jobs/${job.id}` }, job.id.slice(0, 8))),
        ...pointers.map((p) => h("td", { class: "num" }, JSON.stringify(job.parameters[p]))),
        h("td", {}, badge(job.status)),
        h("td", { class: "progress-cell" }, progressBar({ progress: job.progress || 0, status: job.status })),
        ...["kinetic", "strain", "total"].map((e) => h("td", { class: "num" }, fmtNumber((job.energies || {})[e]))))));
      for (const job of sweep.jobs) {
        if (!series.has(job.id) && ["succeeded", "failed", "cancelled"].includes(job.status)) {
          try { series.set(job.id, await api(jobUrl(job.id, "/series"))); } catch (error) {
            if (error instanceof ConnectionLost) throw error;
            series.set(job.id, null);   // no result file (cancelled before its first frame)
          }
        }
      }
      plot.replaceChildren(linePlot(sweep.jobs.map((job, k) => {
        const s = series.get(job.id);
        return { label: showValues(job.parameters), colour: LINE_COLOURS[k % LINE_COLOURS.length],
                 x: (s && s.time) || [], y: (s && s.total_energy) || [] };
      }), "total energy", "No finished job yet."));
      return sweep.status !== "finished";
    }
    return new Poller(load);
  }

  const view = document.getElementById("view");

  function route() {
    if (poller.current) poller.current.stop();
    poller.current = null;
    const [path, query = ""] = location.hash.replace(/^#/, "").split("?");
    const params = new URLSearchParams(query);
    const parts = path.split("/").filter(Boolean);
    let section = "jobs";
    document.title = "MPM dashboard";
    if (parts[0] === "jobs" && parts[1]) {
      poller.current = jobView(view, decodeURIComponent(parts[1]));
    } else if (parts[0] === "sweeps") {
      section = "sweeps";
      poller.current = parts[1] ? sweepView(view, decodeURIComponent(parts[1])) : sweepsView(view);
    } else if (parts[0] === "new") {
      section = "new";
      newJobView(view);
    } else {
      poller.current = jobsView(view, params);
    }
    document.querySelectorAll("[data-nav]").forEach((a) => a.classList.toggle("current", a.dataset.nav === section));
    if (poller.current) poller.current.start();
  }

  window.addEventListener("hashchange", route);
  route();
})();
