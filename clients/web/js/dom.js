// Building the page: elements from tags, attributes and children; the status badge and progress bar.

const SVG_TAGS = new Set(["svg", "g", "path", "line", "polyline", "text", "rect", "circle", "title"]);

/** Element with attributes (on* are listeners) and children (strings become text, never HTML). */
export function h(tag, attrs = {}, ...children) {
  const node = SVG_TAGS.has(tag) ? document.createElementNS("http://www.w3.org/2000/svg", tag) : document.createElement(tag);
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

export function badge(status) {
  return h("span", { class: `badge ${status}` }, status);
}

function percentOf(record) {
  return Math.round(Math.min(1, Math.max(0, record.progress || 0)) * 1000) / 10;
}

export function progressBar(record) {
  const percent = percentOf(record);
  return h("div", { class: `progress ${record.status}`, role: "progressbar", "aria-valuenow": percent,
                    "aria-valuemin": 0, "aria-valuemax": 100 },
    h("div", { class: "progress-track" }, h("div", { class: "progress-fill", style: `width: ${percent}%` })),
    h("span", { class: "progress-label" }, `${percent.toFixed(1)}%`));
}

/** Move a bar made by progressBar to `record`'s progress in place: the fill's width transition
 *  then animates, and the bar is never absent between two updates. */
export function updateProgressBar(bar, record) {
  const percent = percentOf(record);
  bar.className = `progress ${record.status}`;
  bar.setAttribute("aria-valuenow", percent);
  bar.querySelector(".progress-fill").style.width = `${percent}%`;
  bar.querySelector(".progress-label").textContent = `${percent.toFixed(1)}%`;
}

/** Rows of a stats list (<dl class="stats">): [term, value] pairs. */
export function statRows(rows) {
  return rows.map(([term, value]) => h("div", {}, h("dt", {}, term), h("dd", {}, value)));
}

/** Fill a stats list with `rows`, changing only the values when the terms are those shown
 *  already, so a figure is never absent while the page follows a running job. */
export function setStatRows(list, rows) {
  const shown = [...list.children];
  if (shown.length !== rows.length) {
    list.replaceChildren(...statRows(rows));
    return;
  }
  rows.forEach(([, value], i) => {
    const dd = shown[i].querySelector("dd");
    if (dd.textContent !== String(value)) dd.replaceChildren(value);
  });
}

/** Save a blob as a file named `name` (a link clicked on the page's behalf). */
export function saveBlob(blob, name) {
  const url = URL.createObjectURL(blob);
  const link = h("a", { href: url, download: name, hidden: true });
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}
