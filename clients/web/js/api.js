// The service's HTTP API (/v1), called with URLs relative to the dashboard (it is served beside it).
import { auth, banner } from "./banner.js";

export const STATUSES = ["queued", "running", "succeeded", "failed", "cancelled"];
export const ACTIVE = new Set(["queued", "running"]);
export const FINISHED = new Set(["succeeded", "failed", "cancelled"]);

/** An error answer of the service: {"error": {"code", "message", "details"}}. */
export class ApiError extends Error {
  constructor(status, code, message, details) {
    super(message);
    this.status = status;
    this.code = code;
    this.details = details;
  }
}

/** The service could not be reached (or a gateway in front of it answered 502/503/504). */
export class ConnectionLost extends Error {}

/** Call the API (a body is sent as JSON); parses the answer's JSON unless raw. */
export async function api(path, { method = "GET", body, raw = false } = {}) {
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
  if (!response.ok) throw await apiError(response, `${method} ${path}`);
  if (raw) return response;
  return response.status === 204 ? null : response.json();
}

async function apiError(response, request) {
  let payload = null;
  try { payload = await response.json(); } catch (_) { /* not JSON */ }
  const error = (payload && payload.error) || {};
  if (response.status === 401) banner.needToken();
  return new ApiError(response.status, error.code || null,
                      error.message || `${request} answered ${response.status}`, error.details || null);
}

/** GET a resource; null when the service answers 404 (no such job or sweep, or it was deleted). */
export async function getOrNull(path) {
  try {
    return await api(path);
  } catch (error) {
    if (error instanceof ApiError && error.status === 404) return null;
    throw error;
  }
}

/** GET a file of the API as a Blob. */
export async function fetchBlob(path) {
  return (await api(path, { raw: true })).blob();
}

export const jobUrl = (id, tail = "") => `v1/jobs/${encodeURIComponent(id)}${tail}`;
export const sweepUrl = (id, tail = "") => `v1/sweeps/${encodeURIComponent(id)}${tail}`;
