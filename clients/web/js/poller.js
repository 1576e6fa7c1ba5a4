// Polling the service while a view is shown: fast while something runs, backing off when idle.
import { ConnectionLost } from "./api.js";

/**
 * Runs `task` again and again. `task` resolves to true while something is active
 * (then it polls every `fast` ms); when nothing runs the delay doubles up to
 * `idleMax`, after an error up to `errorMax`; a hidden tab polls at most every
 * `hidden` ms and polls at once when it is shown again. `cleanup` runs on stop.
 */
export class Poller {
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

/** The poller of the view on screen (the router replaces it; actions ask it to poll now). */
export const current = { poller: null };

export function pollNow() {
  if (current.poller) current.poller.now();
}
