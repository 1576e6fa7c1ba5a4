// Line plots of series against time (SVG): the energies of a job, the total energies of a sweep's jobs.
import { h } from "./dom.js";
import { fmtNumber } from "./format.js";

export const ENERGY_SERIES = [
  ["kinetic_energy", "kinetic", "var(--kinetic)"],
  ["strain_energy", "strain", "var(--strain)"],
  ["total_energy", "total", "var(--total)"],
  // stored energy minus the work done on the bodies (gravity, loads, walls, damping, ...):
  // constant when energy is conserved; its drift from the start is the balance error
  ["energy_balance", "balance", "var(--balance)"],
];

// The plot's width in its own units when its box is not laid out yet, and the bounds of that
// width: drawn at the width of its box, a plot's text is the size the style sheet says on
// every page (scaling one viewBox to boxes of different widths scaled its fonts with them).
const DEFAULT_WIDTH = 560, MIN_WIDTH = 300, MAX_WIDTH = 1400, HEIGHT = 300;
const MARGIN = { left: 64, right: 16, top: 16, bottom: 40 };

function niceTicks(min, max, count = 5) {
  if (!(max > min)) { max = min + 1; }
  const raw = (max - min) / count;
  const magnitude = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * magnitude).find((s) => s >= raw);
  const ticks = [];
  for (let t = Math.ceil(min / step) * step; t <= max + step * 1e-9; t += step) ticks.push(Number(t.toPrecision(12)));
  return ticks;
}

/** The plot's width for the box it goes in (its content width, within bounds). */
export function plotWidth(box) {
  const style = box && box.isConnected ? getComputedStyle(box) : null;
  const inner = style ? box.clientWidth - parseFloat(style.paddingLeft) - parseFloat(style.paddingRight) : 0;
  return inner > 0 ? Math.round(Math.min(MAX_WIDTH, Math.max(MIN_WIDTH, inner))) : DEFAULT_WIDTH;
}

/** Line plot of the energies against time, and the energy balance's error as a number. */
export function energyPlot(series, width) {
  const present = ENERGY_SERIES.filter(([key]) => Array.isArray(series[key]) && series[key].length);
  const plot = linePlot(present.map(([key, label, colour]) => ({ label, colour, x: series.time || [], y: series[key] })),
                        { yLabel: "energy", emptyText: "No energy data yet.", width });
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

/** Each line's indices kept: about 1500 points a line, the last always, non-finite ones left out. */
function thin(line) {
  const stride = Math.max(1, Math.ceil(line.x.length / 1500));
  const index = [];
  for (let i = 0; i < line.x.length; i += stride) index.push(i);
  if (index[index.length - 1] !== line.x.length - 1) index.push(line.x.length - 1);
  return { ...line, index: index.filter((i) => Number.isFinite(line.y[i]) && Number.isFinite(line.x[i])) };
}

/** The axes' scales: x (time) and y (the values, from zero or below), with the y ticks. */
function scales(thinned, width) {
  const values = thinned.flatMap((line) => line.index.map((i) => line.y[i]));
  const times = thinned.flatMap((line) => line.index.map((i) => line.x[i]));
  let [ymin, ymax] = [Math.min(0, ...values), Math.max(...values)];
  if (!(ymax > ymin)) ymax = ymin + 1;
  const yTicks = niceTicks(ymin, ymax);
  ymin = Math.min(ymin, yTicks[0]);
  ymax = Math.max(ymax, yTicks[yTicks.length - 1]);
  const [xmin, xmax] = [Math.min(...times), Math.max(...times)];
  const { left, right, top, bottom } = MARGIN;
  const x = (t) => left + ((t - xmin) / (xmax - xmin || 1)) * (width - left - right);
  const y = (e) => HEIGHT - bottom - ((e - ymin) / (ymax - ymin)) * (HEIGHT - top - bottom);
  // about one time tick per 90 units of width: their labels never run into each other
  const xTicks = niceTicks(xmin, xmax, Math.max(3, Math.min(6, Math.floor(width / 90)))).filter((t) => t >= xmin && t <= xmax);
  return { x, y, yTicks, xTicks };
}

/** Lines ({label, colour, x, y}) on shared axes, y against time, `width` units wide (see plotWidth). */
export function linePlot(lines, { yLabel, emptyText, width = DEFAULT_WIDTH }) {
  lines = lines.filter((line) => line.x.length >= 2 && line.y.length);
  if (!lines.length) return h("div", { class: "placeholder" }, emptyText);
  const thinned = lines.map(thin);
  const { x, y, yTicks, xTicks } = scales(thinned, width);
  const { left, right, top, bottom } = MARGIN;
  const W = width, H = HEIGHT;
  const grid = yTicks.map((t) => h("g", { class: "tick" },
    h("line", { x1: left, x2: W - right, y1: y(t), y2: y(t) }),
    h("text", { x: left - 8, y: y(t) + 4, "text-anchor": "end" }, fmtNumber(t, 3))));
  const timeTicks = xTicks.map((t) => h("g", { class: "tick x" },
    h("line", { x1: x(t), x2: x(t), y1: H - bottom, y2: H - bottom + 5 }),
    h("text", { x: x(t), y: H - bottom + 19, "text-anchor": "middle" }, fmtNumber(t, 3))));
  const polylines = thinned.map((line) => {
    const points = line.index.map((i) => `${x(line.x[i]).toFixed(1)},${y(line.y[i]).toFixed(1)}`).join(" ");
    return h("polyline", { class: "series", points, style: `stroke: ${line.colour}`, dataset: { label: line.label } },
      h("title", {}, line.label));
  });
  return h("figure", { class: "energy" },
    h("svg", { class: "energy-plot", viewBox: `0 0 ${W} ${H}`, role: "img", "aria-label": `${yLabel} against time` },
      grid, timeTicks,
      h("line", { class: "axis", x1: left, x2: W - right, y1: H - bottom, y2: H - bottom }),
      h("line", { class: "axis", x1: left, x2: left, y1: top, y2: H - bottom }),
      h("text", { class: "axis-label", x: (left + W - right) / 2, y: H - 4, "text-anchor": "middle" }, "time"),
      h("text", { class: "axis-label", x: 14, y: (top + H - bottom) / 2, "text-anchor": "middle",
                  transform: `rotate(-90 14 ${(top + H - bottom) / 2})` }, yLabel),
      polylines),
    h("figcaption", { class: "legend" }, thinned.map((line) =>
      h("span", { class: "legend-item" }, h("i", { style: `background: ${line.colour}` }), line.label))));
}
