// Sweeps (#/sweeps, #/sweeps/ID): the list, and one sweep's jobs side by side with their energies.
import { ConnectionLost, FINISHED, STATUSES, api, getOrNull, jobUrl, sweepUrl } from "./api.js";
import { badge, h, progressBar } from "./dom.js";
import { fmtAge, fmtNumber } from "./format.js";
import { scrollingTable } from "./jobs.js";
import { linePlot, plotWidth } from "./plot.js";
import { Poller, pollNow } from "./poller.js";

const LINE_COLOURS = ["#2563eb", "#dc2626", "#059669", "#d97706", "#7c3aed", "#0891b2", "#db2777", "#65a30d"];
const ENERGIES = ["kinetic", "strain", "total"];
const colourOf = (k) => LINE_COLOURS[k % LINE_COLOURS.length];
const showValues = (parameters) => Object.entries(parameters).map(([p, v]) => `${p} = ${JSON.stringify(v)}`).join(", ");

function sweepRow(sweep) {
  return h("tr", { class: "sweep-row", dataset: { id: sweep.id }, onclick: () => { location.hash = `#/sweeps/${sweep.id}`; } },
    h("td", { class: "name" }, h("a", { href: `#/sweeps/${sweep.id}` }, sweep.name || "(unnamed)"),
      h("div", { class: "id" }, sweep.id.slice(0, 8))),
    h("td", {}, badge(sweep.status)),
    h("td", { class: "num" }, `${sweep.jobs.length - sweep.counts.queued - sweep.counts.running} / ${sweep.jobs.length}`),
    h("td", { class: "progress-cell" }, progressBar({ progress: sweep.progress, status: sweep.status })),
    h("td", {}, Object.keys(sweep.parameters).join(", ")),
    h("td", { class: "age" }, fmtAge(sweep.created_at)));
}

export function sweepsView(container) {
  const body = h("tbody");
  const empty = h("div", { class: "placeholder", hidden: true }, "No sweeps yet (POST /v1/sweeps, mpm sweep).");
  container.replaceChildren(h("section", { class: "card" }, h("div", { class: "toolbar" }, h("h1", {}, "Sweeps")),
    scrollingTable(h("table", { class: "data sweeps" },
      h("thead", {}, h("tr", {}, ["Name", "Status", "Jobs", "Progress", "Parameters", "Age"].map((t) => h("th", {}, t)))),
      body)), empty));
  async function load() {
    const { sweeps } = await api("v1/sweeps");
    body.replaceChildren(...sweeps.map(sweepRow));
    empty.hidden = sweeps.length > 0;
    return sweeps.some((sweep) => sweep.status !== "finished");
  }
  return new Poller(load);
}

/** A row of a sweep's job: its colour in the plot, parameters, status, progress and final energies. */
function sweepJobRow(job, k, pointers) {
  return h("tr", { class: "sweep-job", dataset: { id: job.id, status: job.status } },
    h("td", {}, h("i", { class: "swatch", style: `background: ${colourOf(k)}` }),
      h("a", { href: `#/jobs/${job.id}` }, job.id.slice(0, 8))),
    ...pointers.map((p) => h("td", { class: "num" }, JSON.stringify(job.parameters[p]))),
    h("td", {}, badge(job.status)),
    h("td", { class: "progress-cell" }, progressBar({ progress: job.progress || 0, status: job.status })),
    ...ENERGIES.map((e) => h("td", { class: "num energy" }, fmtNumber((job.energies || {})[e]))));
}

/** A sweep: its jobs side by side (parameters, status, energies) and their total energies in one plot. */
class SweepPage {
  constructor(container, id) {
    Object.assign(this, { container, id, series: new Map() });  // series: job id -> its series, once finished
    this.title = h("h1", {}, "Sweep");
    this.head = h("div", { class: "sweep-state" });
    this.rows = h("tbody");
    this.headRow = h("tr");
    this.plot = h("div", { class: "plot" }, h("div", { class: "placeholder" }, "No energy data yet."));
    this.cancel = h("button", { class: "button danger", onclick: async () => {
      this.cancel.disabled = true; await api(sweepUrl(id, "/cancel"), { method: "POST" }); pollNow(); } }, "Cancel sweep");
    container.replaceChildren(
      h("a", { class: "back", href: "#/sweeps" }, "← All sweeps"),
      h("section", { class: "card job-head" },
        h("div", { class: "job-title" }, h("div", { class: "title-line" }, this.title), h("code", { class: "id" }, id)),
        h("div", { class: "actions" }, this.cancel), this.head),
      h("section", { class: "card" }, h("h2", {}, "Jobs"),
        scrollingTable(h("table", { class: "data sweep-jobs" }, h("thead", {}, this.headRow), this.rows))),
      h("section", { class: "card" }, h("h2", {}, "Total energy of each job"), this.plot));
  }

  /** The sweep; null (and the page says so) when there is no such sweep. */
  async fetchSweep() {
    const sweep = await getOrNull(sweepUrl(this.id));
    if (!sweep) {
      this.container.replaceChildren(h("section", { class: "card" }, h("h1", {}, "No such sweep"),
        h("a", { href: "#/sweeps" }, "Back to all sweeps")));
    }
    return sweep;
  }

  /** The energy series of each job finished since the last poll (null: it has no result file). */
  async fetchSeries(jobs) {
    for (const job of jobs) {
      if (this.series.has(job.id) || !FINISHED.has(job.status)) continue;
      try { this.series.set(job.id, await api(jobUrl(job.id, "/series"))); } catch (error) {
        if (error instanceof ConnectionLost) throw error;
        this.series.set(job.id, null);   // no result file (cancelled before its first frame)
      }
    }
  }

  async load() {
    const sweep = await this.fetchSweep();
    if (!sweep) return false;
    const pointers = Object.keys(sweep.parameters);
    this.title.textContent = sweep.name || "(unnamed sweep)";
    document.title = `${sweep.name || this.id} · MPM`;
    this.head.replaceChildren(badge(sweep.status), progressBar({ progress: sweep.progress, status: sweep.status }),
      h("span", { class: "counts" }, STATUSES.map((s) => `${sweep.counts[s]} ${s}`).join(" · ")));
    this.cancel.disabled = sweep.status === "finished";
    this.headRow.replaceChildren(...["Job", ...pointers, "Status", "Progress"].map((t) => h("th", {}, t)),
      ...["Kinetic", "Strain", "Total"].map((title) => h("th", { class: "energy" }, title)));
    this.rows.replaceChildren(...sweep.jobs.map((job, k) => sweepJobRow(job, k, pointers)));
    await this.fetchSeries(sweep.jobs);
    this.plot.replaceChildren(linePlot(sweep.jobs.map((job, k) => {
      const s = this.series.get(job.id);
      return { label: showValues(job.parameters), colour: colourOf(k), x: (s && s.time) || [], y: (s && s.total_energy) || [] };
    }), { yLabel: "total energy", emptyText: "No finished job yet.", width: plotWidth(this.plot) }));
    return sweep.status !== "finished";
  }
}

export function sweepView(container, id) {
  const page = new SweepPage(container, id);
  return new Poller(() => page.load());
}
