// One job's page (#/jobs/ID): its status and progress, results, energies, scene and solver log.
import { ACTIVE, ApiError, ConnectionLost, api, fetchBlob, getOrNull, jobUrl } from "./api.js";
import { badge, h, progressBar, saveBlob, setStatRows, updateProgressBar } from "./dom.js";
import { fmtDuration, fmtInteger, fmtNumber, fmtTime, wallSeconds } from "./format.js";
import { jsonView } from "./json.js";
import { ENERGY_SERIES, energyPlot, plotWidth } from "./plot.js";
import { Poller, current, pollNow } from "./poller.js";
import { ResultsPanel } from "./results.js";

const SERIES_INTERVAL = 4000;  // ms between reloads of the energy series while a job runs

/** The job's figures as [term, value] rows. */
function recordRows(record) {
  const summary = record.summary || {};
  const running = record.status === "running";
  return [
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
}

/** The energies now, each with its colour, and the balance error. */
function energyRows(energies) {
  return [...ENERGY_SERIES.map(([, label, colour]) => [
    [h("i", { class: "swatch", style: `background: ${colour}` }), `${label} now`], fmtNumber(energies[label])]),
  ["balance error now", fmtNumber(energies.error)]];
}

class JobPage {
  constructor(container, id) {
    Object.assign(this, { container, id, record: null, scene: null, lastSeriesAt: 0, finishedShown: false, logLine: 0 });
    this.results = new ResultsPanel(id);
    this.title = h("h1", {}, "Job");
    this.status = h("span");
    this.stats = h("dl", { class: "stats" });
    this.progress = h("div", { class: "job-progress" });
    this.errorBox = h("div", { class: "diagnostic", hidden: true });
    this.cancel = h("button", { class: "button danger", onclick: () => this.doCancel() }, "Cancel");
    this.download = h("button", { class: "button", onclick: () => this.doDownload() }, "Download HDF5");
    this.remove = h("button", { class: "button ghost danger", onclick: () => this.doDelete() }, "Delete");
    this.plot = h("div", { class: "plot" }, h("div", { class: "placeholder" }, "No energy data yet."));
    this.energyNow = h("dl", { class: "stats energies" });
    this.sceneBox = h("div", { class: "scene" }, h("div", { class: "placeholder" }, "Loading…"));
    this.logBox = h("pre", { class: "log", "aria-label": "solver log" });
    this.logNote = h("div", { class: "placeholder" }, "No log lines yet.");
    container.replaceChildren(h("a", { class: "back", href: "#/jobs" }, "← All jobs"), this.head(),
      h("div", { class: "columns" },
        this.results.node,
        h("section", { class: "card" }, h("h2", {}, "Energy"), this.plot, this.energyNow)),
      h("section", { class: "card" }, h("details", { open: true }, h("summary", {}, h("h2", {}, "Scene")), this.sceneBox)),
      h("section", { class: "card" }, h("details", { open: true }, h("summary", {}, h("h2", {}, "Solver log")),
        this.logNote, this.logBox)));
  }

  head() {
    return h("section", { class: "card job-head" },
      h("div", { class: "job-title" }, h("div", { class: "title-line" }, this.title, this.status),
        h("code", { class: "id" }, this.id)),
      h("div", { class: "actions" }, this.cancel, this.download, this.remove),
      this.progress, this.stats, this.errorBox);
  }

  /** The log lines written since the last read (GET .../log?since=N), appended. */
  async loadLog() {
    const answer = await api(jobUrl(this.id, `/log?since=${this.logLine}`), { raw: true });
    const text = await answer.text();
    this.logLine = Number(answer.headers.get("X-MPM-Next-Line") || this.logLine);
    if (text) this.logBox.append(text);
    this.logNote.hidden = this.logBox.textContent.length > 0;
  }

  renderRecord() {
    const record = this.record;
    this.title.textContent = record.name || "(unnamed)";
    document.title = `${record.name || this.id} · MPM`;
    this.status.replaceChildren(badge(record.status));
    const bar = this.progress.firstElementChild;
    if (bar) updateProgressBar(bar, record);
    else this.progress.append(progressBar(record));
    setStatRows(this.stats, recordRows(record));
    setStatRows(this.energyNow, energyRows(record.energies || {}));
    this.errorBox.hidden = !record.error;
    this.errorBox.replaceChildren(h("strong", {}, "Diagnostic"), h("pre", {}, record.error || ""));
    const active = ACTIVE.has(record.status);
    this.cancel.disabled = !active;
    this.download.disabled = active;
    this.remove.disabled = active;
  }

  async loadSeries() {
    this.lastSeriesAt = Date.now();
    try {
      this.plot.replaceChildren(energyPlot(await api(jobUrl(this.id, "/series")), plotWidth(this.plot)));
    } catch (error) {
      if (error instanceof ConnectionLost) throw error;
      if (!(error instanceof ApiError && error.status === 409)) {
        this.plot.replaceChildren(h("div", { class: "placeholder" }, `No energy data: ${error.message}`));
      }
    }
  }

  /** The job's record; null (and the page says so) when there is no such job. */
  async fetchRecord() {
    const record = await getOrNull(jobUrl(this.id));
    if (record) return record;
    this.container.replaceChildren(h("section", { class: "card" }, h("h1", {}, "No such job"),
      h("p", {}, "It may have been deleted. "), h("a", { href: "#/jobs" }, "Back to all jobs")));
    if (current.poller) current.poller.stop();
    return null;
  }

  async load() {
    this.record = await this.fetchRecord();
    if (!this.record) return false;
    const running = this.record.status === "running";
    this.renderRecord();
    if (this.scene === null) {
      this.scene = await api(jobUrl(this.id, "/scene"));
      this.sceneBox.replaceChildren(jsonView(this.scene));
    }
    await this.results.update(this.record, this.scene);
    if (running && Date.now() - this.lastSeriesAt > SERIES_INTERVAL) await this.loadSeries();
    if (running) await this.loadLog();
    if (!ACTIVE.has(this.record.status) && !this.finishedShown) {
      this.finishedShown = true;
      await this.loadSeries();
      await this.loadLog();
    }
    return ACTIVE.has(this.record.status);
  }

  async doCancel() {
    this.cancel.disabled = true;
    try {
      await api(jobUrl(this.id, "/cancel"), { method: "POST" });
    } catch (error) {
      if (!(error instanceof ConnectionLost)) alert(`Could not cancel: ${error.message}`);
    }
    pollNow();
  }

  async doDownload() {
    this.download.disabled = true;
    try {
      saveBlob(await fetchBlob(jobUrl(this.id, "/result.h5")), `${this.record.name || this.id}.h5`);
    } catch (error) {
      if (!(error instanceof ConnectionLost)) alert(`Could not download: ${error.message}`);
    } finally {
      this.download.disabled = ACTIVE.has(this.record.status);
    }
  }

  async doDelete() {
    if (!confirm(`Delete job "${this.record.name || this.id}" and its files?`)) return;
    try {
      await api(jobUrl(this.id), { method: "DELETE" });
      location.hash = "#/jobs";
    } catch (error) {
      if (!(error instanceof ConnectionLost)) alert(`Could not delete: ${error.message}`);
    }
  }
}

export function jobView(container, id) {
  const page = new JobPage(container, id);
  return new Poller(() => page.load(), { cleanup: () => page.results.stop() });
}
