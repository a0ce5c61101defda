"""Shortest collision-free path from the start to the goal circle among circular obstacles
(no ROS imports): the denominator of the path length ratio (PLR) of the difficulty proxy.

Every non-traversable obstacle is a disc of its collision radius plus the vehicle's clearance
(half its width). The shortest path among discs is made of straight segments tangent to the
discs and arcs along their rims, so a *tangent visibility graph* holds it exactly:

- nodes: the start S, the goal centre G, and the tangent points of every segment tangent to two
  discs (four per disjoint pair), from S to each disc and from G to each disc;
- edges: those tangent segments when no disc blocks them, and the arcs between consecutive
  nodes on the same rim when no other disc covers the arc;
- the goal is a circle of radius R around G: a path ends where it first touches the circle, and
  a shortest path to a circle meets it head on (towards G), so the last leg of every candidate is
  a segment towards G, shortened by R (checked for collisions only outside the goal circle).

- a disc that reaches into the goal circle (the worker removes obstacles by their centre's
  distance, so a disc centred just outside the safety radius does) can hide every head-on leg
  near it; a path then ends where the disc's rim crosses the goal circle. Those crossing points
  are nodes too, joined to the goal at no cost, to the start by a straight segment and to every
  other disc by its tangents from the crossing point, and along their own rim by arcs.

Dijkstra on this graph gives the exact length (to floating point). The tests check it against
analytic detours and a fine grid search, with discs clear of the goal circle and reaching into it.
"""

import heapq
import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple


EPS = 1e-9


@dataclass(frozen=True)
class Disc:
    x: float
    y: float
    r: float


@dataclass
class OptimalPath:
    length: float  #: [m] to the goal circle; inf if unreachable
    points: List[Tuple[float, float]]  #: polyline (arcs sampled every ~0.5 m), start .. goal circle


def _seg_blocked(p, q, discs, skip=(), tol=1e-7):
    """True if segment p-q passes through the interior of a disc (touching the rim is allowed)."""
    px, py = p
    dx, dy = q[0] - px, q[1] - py
    L2 = dx * dx + dy * dy
    for k, d in enumerate(discs):
        if k in skip:
            continue
        if L2 < EPS:
            t = 0.0
        else:
            t = max(0.0, min(1.0, ((d.x - px) * dx + (d.y - py) * dy) / L2))
        cx, cy = px + t * dx - d.x, py + t * dy - d.y
        if cx * cx + cy * cy < (d.r - tol) ** 2:
            return True
    return False


def _point_tangents(p, d):
    """Tangent points on disc d of the two lines through p (p outside d)."""
    vx, vy = p[0] - d.x, p[1] - d.y
    dist = math.hypot(vx, vy)
    if dist <= d.r + EPS:
        return []
    base = math.atan2(vy, vx)
    off = math.acos(d.r / dist)
    return [(d.x + d.r * math.cos(base + s * off), d.y + d.r * math.sin(base + s * off)) for s in (1, -1)]


def _bitangents(a, b):
    """Tangent point pairs (on a, on b) of the segments tangent to both discs."""
    out = []
    dx, dy = b.x - a.x, b.y - a.y
    d = math.hypot(dx, dy)
    if d < EPS:
        return out
    base = math.atan2(dy, dx)
    # Outer tangents: both points at the same normal angle.
    if d > abs(a.r - b.r):
        off = math.acos((a.r - b.r) / d)
        for s in (1, -1):
            ang = base + s * off
            out.append(
                (
                    (a.x + a.r * math.cos(ang), a.y + a.r * math.sin(ang)),
                    (b.x + b.r * math.cos(ang), b.y + b.r * math.sin(ang)),
                )
            )
    # Inner tangents: only for disjoint discs.
    if d > a.r + b.r:
        off = math.acos((a.r + b.r) / d)
        for s in (1, -1):
            ang = base + s * off
            out.append(
                (
                    (a.x + a.r * math.cos(ang), a.y + a.r * math.sin(ang)),
                    (b.x - b.r * math.cos(ang), b.y - b.r * math.sin(ang)),
                )
            )
    return out


def _circle_crossings(c, R, d):
    """Points where the rim of disc d crosses the circle of radius R around c."""
    dx, dy = d.x - c[0], d.y - c[1]
    L = math.hypot(dx, dy)
    if L < EPS or L >= R + d.r or L <= abs(R - d.r):
        return []
    a = (R * R - d.r * d.r + L * L) / (2 * L)  # along c -> d
    h = math.sqrt(max(0.0, R * R - a * a))
    mx, my = c[0] + a * dx / L, c[1] + a * dy / L
    return [(mx - h * dy / L, my + h * dx / L), (mx + h * dy / L, my - h * dx / L)]


def _arc_free(d_index, a0, a1, discs, r):
    """The arc of disc d_index from angle a0 counter-clockwise to a1 is not inside another disc."""
    d = discs[d_index]
    span = (a1 - a0) % (2 * math.pi)
    n = max(2, int(span * r / 0.25) + 1)
    for i in range(1, n):
        ang = a0 + span * i / n
        x, y = d.x + r * math.cos(ang), d.y + r * math.sin(ang)
        for k, o in enumerate(discs):
            if k != d_index and (x - o.x) ** 2 + (y - o.y) ** 2 < (o.r - 1e-7) ** 2:
                return False
    return True


def shortest_path(
    start: Sequence[float], goal: Sequence[float], goal_radius: float, discs: Sequence[Disc]
) -> OptimalPath:
    """Exact shortest path from `start` to the circle of `goal_radius` around `goal`.

    A disc that holds the start or the goal centre is shrunk to just exclude it (the worker's
    safety radius keeps that from happening in a real scenario)."""
    S, G = (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1]))
    if math.dist(S, G) <= goal_radius:
        return OptimalPath(0.0, [S])
    ds = []
    for d in discs:
        r = d.r
        for p in (S, G):
            r = min(r, math.dist(p, (d.x, d.y)) - 1e-6)
        if r > 1e-6:
            ds.append(Disc(d.x, d.y, r))
    nodes: List[Tuple[float, float]] = [S, G]
    on_disc: List[Optional[int]] = [None, None]
    edges: List[List[Tuple[int, float]]] = [[], []]

    def add_node(p, k):
        nodes.append(p)
        on_disc.append(k)
        edges.append([])
        return len(nodes) - 1

    def add_edge(i, j, w):
        edges[i].append((j, w))
        edges[j].append((i, w))

    def goal_leg_free(p, skip):
        # Only the part outside the goal circle must be free.
        L = math.dist(p, G)
        if L <= goal_radius:
            return True
        t = (L - goal_radius) / L
        q = (p[0] + t * (G[0] - p[0]), p[1] + t * (G[1] - p[1]))
        return not _seg_blocked(p, q, ds, skip)

    # Start and goal straight to each other, and tangents to every disc.
    if goal_leg_free(S, ()):
        add_edge(0, 1, math.dist(S, G) - goal_radius)
    for k, d in enumerate(ds):
        for t in _point_tangents(S, d):
            if not _seg_blocked(S, t, ds, (k,)):
                add_edge(0, add_node(t, k), math.dist(S, t))
        for t in _point_tangents(G, d):
            if math.dist(t, G) > goal_radius and goal_leg_free(t, (k,)):
                add_edge(add_node(t, k), 1, math.dist(t, G) - goal_radius)
    # Where a disc's rim crosses the goal circle (outside every other disc): an end point.
    for k, d in enumerate(ds):
        for c in _circle_crossings(G, goal_radius, d):
            if any((c[0] - o.x) ** 2 + (c[1] - o.y) ** 2 < (o.r - 1e-7) ** 2 for j, o in enumerate(ds) if j != k):
                continue
            n = add_node(c, k)
            add_edge(n, 1, 0.0)
            if not _seg_blocked(S, c, ds):
                add_edge(0, n, math.dist(S, c))
            for j, e in enumerate(ds):
                if j == k:
                    continue
                for t in _point_tangents(c, e):
                    if not _seg_blocked(c, t, ds, (j,)):
                        add_edge(n, add_node(t, j), math.dist(c, t))
    for i in range(len(ds)):
        for j in range(i + 1, len(ds)):
            for p, q in _bitangents(ds[i], ds[j]):
                if not _seg_blocked(p, q, ds, (i, j)):
                    add_edge(add_node(p, i), add_node(q, j), math.dist(p, q))
    # Arcs between consecutive nodes on each rim.
    for k, d in enumerate(ds):
        idx = [n for n in range(len(nodes)) if on_disc[n] == k]
        if len(idx) < 2:
            continue
        ang = sorted((math.atan2(nodes[n][1] - d.y, nodes[n][0] - d.x), n) for n in idx)
        for m in range(len(ang)):
            a0, n0 = ang[m]
            a1, n1 = ang[(m + 1) % len(ang)]
            span = (a1 - a0) % (2 * math.pi)
            if _arc_free(k, a0, a1, ds, d.r):
                add_edge(n0, n1, d.r * span)
    dist, prev = _dijkstra(edges, 0, 1)
    if not math.isfinite(dist[1]):
        return OptimalPath(math.inf, [])
    return OptimalPath(dist[1], _polyline(_chain(prev, 0, 1), nodes, on_disc, ds, dist, G, goal_radius))


def _dijkstra(edges, source: int, target: int):
    """Distances from `source` (math.inf where unreached) and each node's predecessor, settled up
    to `target`."""
    dist = [math.inf] * len(edges)
    prev = [-1] * len(edges)
    dist[source] = 0.0
    heap = [(0.0, source)]
    while heap:
        du, u = heapq.heappop(heap)
        if du > dist[u]:
            continue
        if u == target:
            break
        for v, w in edges[u]:
            if du + w < dist[v] - 1e-12:
                dist[v], prev[v] = du + w, u
                heapq.heappush(heap, (dist[v], v))
    return dist, prev


def _chain(prev, source: int, target: int) -> List[int]:
    chain = [target]
    while chain[-1] != source:
        chain.append(prev[chain[-1]])
    chain.reverse()
    return chain


def _polyline(chain, nodes, on_disc, ds, dist, G, goal_radius) -> List[Tuple[float, float]]:
    """The path's points: straight legs between graph nodes, arcs along a disc's rim sampled every
    0.5 m, and the last leg cut at the goal circle (node 1 is the goal)."""
    pts = [nodes[chain[0]]]
    for a, b in zip(chain, chain[1:]):
        if b == 1:
            p = nodes[a]
            L = math.dist(p, G)
            if L <= goal_radius + 1e-9:  # a rim crossing of the goal circle: the path ends here
                continue
            t = (L - goal_radius) / L
            pts.append((p[0] + t * (G[0] - p[0]), p[1] + t * (G[1] - p[1])))
        elif on_disc[a] is not None and on_disc[a] == on_disc[b]:
            d = ds[on_disc[a]]
            a0 = math.atan2(nodes[a][1] - d.y, nodes[a][0] - d.x)
            a1 = math.atan2(nodes[b][1] - d.y, nodes[b][0] - d.x)
            ccw = (a1 - a0) % (2 * math.pi)
            # The way the graph went round: the span whose arc length is the edge's weight.
            span = ccw if abs(d.r * ccw - (dist[b] - dist[a])) < 1e-6 else ccw - 2 * math.pi
            n = max(1, int(abs(span) * d.r / 0.5))
            pts += [
                (d.x + d.r * math.cos(a0 + span * i / n), d.y + d.r * math.sin(a0 + span * i / n))
                for i in range(1, n + 1)
            ]
        else:
            pts.append(nodes[b])
    return pts


def obstacle_discs(scenario: dict, clearance: float, placed_mask: Optional[Sequence[bool]] = None) -> List[Disc]:
    """Discs of the placed, non-traversable obstacles of a scenario, inflated by `clearance` [m].

    placed_mask: per flattened instance, False for obstacles the worker did not place (removed
    by a safety radius); by default the safety radii are applied here as the worker does."""
    from asg_scenario.catalogue import MESHES, TRAVERSABLE_HEIGHT

    op = scenario["operational"]
    out = []
    k = 0
    for layout in scenario["structural"]["layouts"]:
        mesh = MESHES[layout["mesh_name"]]
        for inst in layout["instances"]:
            placed = inst["visible"]
            if placed_mask is not None:
                placed = placed and placed_mask[k]
            else:
                for cx, cy in ((op["start_x"], op["start_y"]), (op["goal_x"], op["goal_y"])):
                    if math.hypot(inst["x"] - cx, inst["y"] - cy) < op["safety_radius"]:
                        placed = False
            k += 1
            if not placed or mesh.height * inst["scale"] <= TRAVERSABLE_HEIGHT:
                continue
            out.append(Disc(inst["x"], inst["y"], mesh.collision_radius * inst["scale"] + clearance))
    return out
