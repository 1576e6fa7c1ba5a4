// A JSON document shown line by line (a scene; its validation errors next to their lines) and as text.
import { h } from "./dom.js";

/**
 * The document as indented lines; each line carries `data-path` in the scene's
 * error notation (`bodies[1].geometry.radius`), and `errors` (path -> messages)
 * are shown next to their line. An error whose path is not in the document
 * (a missing key) goes next to its nearest ancestor that is.
 */
export function jsonView(document_, errors = new Map()) {
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
export function formatJson(value, depth = 0) {
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
