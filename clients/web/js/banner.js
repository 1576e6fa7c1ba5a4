// The banner under the top bar: the connection to the service lost and restored, the API token asked for.
import { h } from "./dom.js";

// The API token lives in this tab's session storage: gone when the tab closes, never in a URL.
export const auth = {
  get token() { return sessionStorage.getItem("mpm.token") || ""; },
  set token(value) { value ? sessionStorage.setItem("mpm.token", value) : sessionStorage.removeItem("mpm.token"); },
};

export const banner = {
  node: document.getElementById("banner"),
  state: "ok",
  retry: () => {},        // "Retry now" (set by the router: poll the current view at once)
  tokenSaved: () => {},   // after a token is entered (set by the router: show the view again)
  connectionLost() {
    if (this.state === "lost") return;
    this.state = "lost";
    this.show("warning", "Lost the connection to the service. Retrying…",
              h("button", { class: "button small", onclick: () => this.retry() }, "Retry now"));
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
      this.tokenSaved();
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
