// The job list (#/jobs[?status=S]): every job with its status and progress, newest first.
import { ACTIVE, STATUSES, api } from "./api.js";
import { badge, h, progressBar } from "./dom.js";
import { fmtAge, fmtDuration, fmtInteger, fmtNumber, fmtTime } from "./format.js";
import { Poller, pollNow } from "./poller.js";

const PAGE_SIZE = 50;
const COLUMNS = ["Name", "Status", "Progress", "Sim time", "Steps/s", "ETA", "Age"];

export function jobsView(container, params) {
  const status = STATUSES.includes(params.get("status")) ? params.get("status") : "";
  let pages = 1;
  const body = h("tbody");
  const empty = h("div", { class: "placeholder", hidden: true });
  const more = h("button", { class: "button ghost", hidden: true, onclick: () => { pages += 1; pollNow(); } },
    "Show older jobs");
  const filters = h("div", { class: "filters", role: "group", "aria-label": "status filter" },
    ["", ...STATUSES].map((s) => h("a", {
      class: s === status ? "chip active" : "chip", href: s ? `#/jobs?status=${s}` : "#/jobs",
      dataset: { status: s || "all" },
    }, s || "all")));
  const table = h("table", { class: "data jobs" },
    h("thead", {}, h("tr", {}, COLUMNS.map((title) => h("th", {}, title)))), body);
  container.replaceChildren(h("section", { class: "card" },
    h("div", { class: "toolbar" }, h("h1", {}, "Jobs"), filters),
    scrollingTable(table), empty, more));

  async function load() {
    const { jobs, cursor } = await fetchJobs(status, pages);
    body.replaceChildren(...jobs.map(jobRow));
    empty.hidden = jobs.length > 0;
    empty.replaceChildren(status ? `No ${status} jobs.` : "No jobs yet. ",
                          status ? "" : h("a", { href: "#/new" }, "Submit one."));
    more.hidden = !cursor;
    return jobs.some((job) => ACTIVE.has(job.status));
  }
  return new Poller(load);
}

/** The first `pages` pages of jobs (with `status` only, when given) and the cursor of the next. */
async function fetchJobs(status, pages) {
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
  return { jobs, cursor };
}

/**
 * A table that scrolls sideways in its card when it is wider than the card, with a cue while
 * columns are out of sight: a shadow on the side they are, and a line under it that says so.
 */
export function scrollingTable(table) {
  const hint = h("div", { class: "scroll-hint", hidden: true }, "Scroll sideways for more columns →");
  const wrap = h("div", { class: "table-wrap", tabindex: 0, "aria-label": "table (scrolls sideways)" }, table);
  const scroller = h("div", { class: "table-scroller" }, wrap,
    h("div", { class: "table-fade left" }), h("div", { class: "table-fade right" }));
  const cue = () => {
    const hidden = wrap.scrollWidth - wrap.clientWidth;
    scroller.classList.toggle("more-right", hidden > 1 && wrap.scrollLeft < hidden - 1);
    scroller.classList.toggle("more-left", hidden > 1 && wrap.scrollLeft > 1);
    hint.hidden = hidden <= 1;
  };
  wrap.addEventListener("scroll", cue, { passive: true });
  new ResizeObserver(cue).observe(wrap);
  new MutationObserver(cue).observe(table, { childList: true, subtree: true });
  return h("div", {}, scroller, hint);
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
