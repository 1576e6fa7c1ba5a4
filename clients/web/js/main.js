// The MPM dashboard: a job table, a job page, a "new job" form and sweeps over the HTTP API (/v1).
// Plain JavaScript modules, no build step, no network access beyond the service itself.
// Routes (hash): #/jobs[?status=S], #/jobs/ID, #/sweeps, #/sweeps/ID, #/new.
import { banner } from "./banner.js";
import { jobView } from "./job.js";
import { jobsView } from "./jobs.js";
import { newJobView } from "./newjob.js";
import { current, pollNow } from "./poller.js";
import { sweepView, sweepsView } from "./sweeps.js";

const view = document.getElementById("view");

/** The view of the hash and the section of the top bar it belongs to. */
function showView(parts, params) {
  if (parts[0] === "jobs" && parts[1]) return ["jobs", jobView(view, decodeURIComponent(parts[1]))];
  if (parts[0] === "sweeps") {
    return ["sweeps", parts[1] ? sweepView(view, decodeURIComponent(parts[1])) : sweepsView(view)];
  }
  if (parts[0] === "new") {
    newJobView(view);
    return ["new", null];
  }
  return ["jobs", jobsView(view, params)];
}

function route() {
  if (current.poller) current.poller.stop();
  current.poller = null;
  const [path, query = ""] = location.hash.replace(/^#/, "").split("?");
  document.title = "MPM dashboard";
  const [section, poller] = showView(path.split("/").filter(Boolean), new URLSearchParams(query));
  current.poller = poller;
  document.querySelectorAll("[data-nav]").forEach((a) => a.classList.toggle("current", a.dataset.nav === section));
  if (poller) poller.start();
}

banner.retry = pollNow;
banner.tokenSaved = route;
window.addEventListener("hashchange", route);
route();
