"""The compiled inside test of triangle meshes (solver/mesh.py): the even-odd rule along +z.

A point is inside when its vertical ray upwards crosses the surface an odd number of
times. Where the ray passes exactly through an edge or a vertex of the projected mesh,
each edge decides which side the point is on as if the point were moved by (e, e^2)
for an infinitely small e (simulation of simplicity): the decision is computed from the
edge's endpoints taken in one fixed order, so the two triangles sharing an edge never
both count the point, nor both miss it, and the crossing count stays right.
"""
from __future__ import annotations

from solver.jit import njit


@njit(cache=True, inline="always")
def _side(ax, ay, bx, by, px, py):
    """(w, s): w is the orientation of p against the edge a -> b (twice the signed area),
    s its sign under the perturbation; both computed with the endpoints in lexicographic
    order, so that the edge b -> a gives exactly -w and -s."""
    flip = 1.0
    if ax > bx or (ax == bx and ay > by):
        ax, ay, bx, by = bx, by, ax, ay
        flip = -1.0
    w = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
    if w != 0.0:
        s = 1.0 if w > 0.0 else -1.0
    elif ay != by:
        s = 1.0 if ay > by else -1.0     # d w / d px = ay - by
    else:
        s = 1.0 if bx > ax else (-1.0 if bx < ax else 0.0)   # d w / d py = bx - ax
    return flip * w, flip * s


@njit(cache=True)
def inside_mesh(points, triangles, lower, inverse, nx, ny, start, items, out):
    """out[p] = the point p is inside the closed mesh (triangles (T, 3, 3), binned in xy
    on an nx x ny grid from `lower` with `inverse` bins per length; CSR start/items)."""
    for p in range(points.shape[0]):
        px, py, pz = points[p, 0], points[p, 1], points[p, 2]
        fx = (px - lower[0]) * inverse[0]
        fy = (py - lower[1]) * inverse[1]
        if fx < 0.0 or fy < 0.0 or fx > nx or fy > ny:
            out[p] = False
            continue
        b = min(int(fx), nx - 1) * ny + min(int(fy), ny - 1)
        crossings = 0
        for k in range(start[b], start[b + 1]):
            t = items[k]
            x0, y0, z0 = triangles[t, 0, 0], triangles[t, 0, 1], triangles[t, 0, 2]
            x1, y1, z1 = triangles[t, 1, 0], triangles[t, 1, 1], triangles[t, 1, 2]
            x2, y2, z2 = triangles[t, 2, 0], triangles[t, 2, 1], triangles[t, 2, 2]
            w0, s0 = _side(x1, y1, x2, y2, px, py)
            if s0 == 0.0:
                continue
            w1, s1 = _side(x2, y2, x0, y0, px, py)
            if s1 != s0:
                continue
            w2, s2 = _side(x0, y0, x1, y1, px, py)
            if s2 != s0:
                continue
            total = w0 + w1 + w2
            # barycentric weights of the same sign: z stays within the triangle's corners
            z = (w0 * z0 + w1 * z1 + w2 * z2) / total if total != 0.0 else (z0 + z1 + z2) / 3.0
            if z > pz:
                crossings += 1
        out[p] = (crossings & 1) == 1
