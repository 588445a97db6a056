"""RRT-Connect as one numba kernel over the sphere collision model (the ideas of VAMP, in Python).

The whole search loop runs compiled: two trees in preallocated arrays, brute-force nearest
neighbours over each tree's contiguous node array, extend/connect steps of at most ``range``
(L2, like OMPL's RRTConnect), VAMP's balanced trees and dynamic domains (:func:`tuning`: the
smaller tree extends while the other has twice its nodes; a node whose extension failed only
takes samples within its domain), and every edge checked at the motion resolution (L∞ step, the states
of :func:`maru_planner.planning.space.edge_states`, computed the same way) in coarse-to-fine
bisection order with an early exit on the first colliding state. Each state is classified by
:func:`classify`: forward kinematics once, then robot spheres against the scene primitives and the
SRDF's self-collision pairs in a tight loop down the sphere checker's bounding hierarchy (group,
cluster, sphere), a sphere placed only where its cluster's bound reaches something; it answers
exactly as the checker's ``classify_state`` does. Scenes large enough for the checker's grid broad
phase go through its own scan (:func:`maru_planner.collision.sphere_kernels.scan_nb`).

The search is a resumable state machine (``st``, :data:`STATE_FIELDS`): :func:`run` proposes one
edge at a time and applies its verdict, and returns to the caller

* every ``max_edges`` edges (:data:`RUNNING`), so the caller can evaluate OMPL's termination
  condition;
* when a tree's arrays are full (:data:`FULL`): the caller grows them and calls again;
* when some of the edge's states are only *ambiguous* on the sphere model (outer spheres touch, no
  inner ball does), lie within ``exact_near`` of the start or goal, and ``confirm`` is set
  (:data:`NEED_EXACT`): those states are in ``amb_states[:st[N_AMB]]``, the caller decides them on
  the exact model and passes the edge's verdict to the next call;
* with a solution (:data:`SOLVED`): :func:`solution_path`.

Deterministic: the samples come from a splitmix64 generator whose state (``rng``) the caller seeds.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from maru_planner.collision.batch_fk import joint_poses_nb, place_members, place_points, row_distance
from maru_planner.collision.sphere_kernels import (
    AMBIGUOUS,
    COLLIDING,
    VALID,
    obstacle_distance,
    scan_nb,
    unpack_robot,
    unpack_scene,
)
from maru_planner.collision.support_bounds import NO_SHAPE, convex_bound, load_primitive, new_records, place_shape

SOLVED, RUNNING, NEED_EXACT, FULL = 0, 1, 2, 3  # what run() returns
CLEAR_BY = 1e-9  # m: GJK stops once a pair's bound is this far past the padding (clear_on_shapes)
BALANCE, DOMAIN_RADIUS, DOMAIN_ALPHA, DOMAIN_MIN_RADIUS = range(4)  # fields of the tuning array (tuning())
DIRECT, EXTEND, CONNECT = 0, 1, 2  # phases: the straight start-goal edge, extend toward a sample, connect

#: Fields of the int64 search state ``st`` (index = position).
STATE_FIELDS = ("phase", "tree", "from", "target", "pending", "reached", "n0", "n1", "checks", "n_amb",
                "link0", "link1", "duplicate")  # fmt: skip
(PHASE, TREE, FROM, TARGET, PENDING, REACHED, N0, N1, CHECKS, N_AMB, LINK0, LINK1, DUPLICATE) = range(len(STATE_FIELDS))


def new_state(
    start: np.ndarray, goal: np.ndarray, capacity: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Trees (2, capacity, dim) holding the start (tree 0) and the goal (tree 1), parents, domain radii, ``st``."""
    dim = len(start)
    nodes = np.zeros((2, capacity, dim))
    nodes[0, 0], nodes[1, 0] = start, goal
    parent = np.full((2, capacity), -1, dtype=np.int64)
    radius = np.full((2, capacity), np.inf)
    st = np.zeros(len(STATE_FIELDS), dtype=np.int64)
    st[N0] = st[N1] = 1
    st[PHASE] = DIRECT
    return nodes, parent, radius, st


def grow(nodes: np.ndarray, parent: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The trees' arrays with twice the capacity (contents kept)."""
    cap = nodes.shape[1]
    bigger = np.zeros((2, 2 * cap, nodes.shape[2]))
    bigger[:, :cap] = nodes
    parents = np.full((2, 2 * cap), -1, dtype=np.int64)
    parents[:, :cap] = parent
    radii = np.full((2, 2 * cap), np.inf)
    radii[:, :cap] = radius
    return bigger, parents, radii


def tuning(balance: bool, domain_radius: float, domain_alpha: float, domain_min_radius: float) -> np.ndarray:
    """The kernel's tree balancing and dynamic-domain settings (:func:`run`); ``domain_radius`` 0 = no domains."""
    return np.array([float(balance), domain_radius, domain_alpha, domain_min_radius])


def seed_rng(seed: int) -> np.ndarray:
    """The generator state for :func:`run` (uint64 array of one)."""
    return np.array([seed % 2**64], dtype=np.uint64)


@njit(cache=True, inline="always")
def uniform(rng):
    """splitmix64 step → float in [0, 1)."""
    rng[0] += np.uint64(0x9E3779B97F4A7C15)
    z = rng[0]
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@njit(cache=True)
def _nearest(tree_nodes, count, q):
    return _nearest_with_distance(tree_nodes, count, q)[0]


@njit(cache=True)
def _nearest_with_distance(tree_nodes, count, q):
    """(index, L2 distance) of the node of ``tree_nodes[:count]`` nearest ``q``."""
    best, best_d = 0, np.inf
    dim = q.shape[0]
    for i in range(count):
        d = 0.0
        for a in range(dim):
            e = tree_nodes[i, a] - q[a]
            d += e * e
        if d < best_d:
            best, best_d = i, d
    return best, np.sqrt(best_d)


@njit(cache=True)
def _steer(q_from, q_to, max_range, out):
    """Write into ``out`` the point at most ``max_range`` (L2) from ``q_from`` toward ``q_to``; True if it is q_to."""
    dim = q_from.shape[0]
    dist = 0.0
    for a in range(dim):
        e = q_to[a] - q_from[a]
        dist += e * e
    dist = np.sqrt(dist)
    if dist <= max_range:
        out[:] = q_to
        return True
    f = max_range / dist
    for a in range(dim):
        out[a] = q_from[a] + f * (q_to[a] - q_from[a])
    return False


@njit(cache=True)
def bisection_order(n):
    """Indices 0..n-1: the last (the edge's end), then midpoints of ever finer halves (checker.bisection_order
    with include_first=False)."""
    order, queue = edge_buffers(n)
    _bisection_order_into(n, order, queue)
    return order


@njit(cache=True)
def edge_buffers(n):
    """Work arrays of :func:`_bisection_order_into` for edges of up to ``n`` states: the order and a queue."""
    return np.empty(n, dtype=np.int64), np.empty((2 * n + 1, 2), dtype=np.int64)


@njit(cache=True, inline="always")
def _bisection_order_into(n, out, queue):
    """:func:`bisection_order` of ``n`` into ``out[:n]``; ``queue`` holds the segments still to halve (each midpoint
    adds two)."""
    out[0] = n - 1
    filled = 1
    queue[0, 0], queue[0, 1] = -1, n - 1
    head, tail = 0, 1
    while head < tail:
        a, b = queue[head, 0], queue[head, 1]
        head += 1
        if b - a < 2:
            continue
        m = (a + b) // 2
        out[filled] = m
        filled += 1
        queue[tail, 0], queue[tail, 1] = a, m
        tail += 1
        queue[tail, 0], queue[tail, 1] = m, b
        tail += 1


@njit(cache=True)
def obstacle_bounds(scene):
    """World axis-aligned bounds (n, 6: lo, hi) of an unpack_scene tuple's obstacles, widened by a nanometre so
    that rounding never lets a point beyond them be nearer to the obstacle than it is to them."""
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, exact = scene
    nb, ns = box_c.shape[0], sph_c.shape[0]
    out = np.empty((exact.shape[0], 6))
    for k in range(exact.shape[0]):
        for a in range(3):
            if k < nb:
                c, h = box_c[k, a], 0.0
                for b in range(3):
                    h += abs(box_r[k, a, b]) * box_h[k, b]
            elif k < nb + ns:
                c, h = sph_c[k - nb, a], sph_r[k - nb]
            else:
                i = k - nb - ns
                c = cyl_c[i, a]
                h = abs(cyl_a[i, a]) * cyl_h[i] + np.sqrt(max(1.0 - cyl_a[i, a] ** 2, 0.0)) * cyl_r[i]
            out[k, a], out[k, 3 + a] = c - h - 1e-9, c + h + 1e-9
    return out


@njit(cache=True)
def work_arrays(robot, scene):
    """:func:`classify`'s work arrays for unpack_robot/unpack_scene tuples: joint rotations and positions, world
    centres of the groups', clusters' and spheres' bounds, which groups' clusters and which clusters' spheres
    are placed (all rewritten per state), and the scene's :func:`obstacle_bounds`."""
    nj, ns, ng, nc = robot[0].shape[0], robot[6].shape[0], robot[11].shape[0], robot[17].shape[0]
    return (np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((ng, 3)), np.empty((nc, 3)), np.empty((ns, 3)),
            np.zeros(ng, dtype=np.bool_), np.zeros(nc, dtype=np.bool_), obstacle_bounds(scene))  # fmt: skip


@njit(cache=True, inline="always")
def _box_gap(bounds, k, lo0, lo1, lo2, hi0, hi1, hi2):
    """How far the box ``[lo, hi]`` lies outside obstacle ``k``'s axis-aligned bounds along the axis where it lies
    farthest (<= 0: they overlap). One comparison of the largest excess, not six short-circuited ones: their
    branches mispredict."""
    return max(max(bounds[k, 0] - hi0, lo0 - bounds[k, 3]), max(bounds[k, 1] - hi1, lo1 - bounds[k, 4]),
               max(bounds[k, 2] - hi2, lo2 - bounds[k, 5]))  # fmt: skip


@njit(cache=True, inline="always")
def _beyond(world, i, reach, bounds, k):
    """Whether ``world[i]`` is at least ``reach`` outside obstacle ``k``'s axis-aligned bounds along some axis
    (then it is that far from the obstacle: a test without the obstacle's rotation or a square root)."""
    x, y, z = world[i, 0], world[i, 1], world[i, 2]
    return _box_gap(bounds, k, x, y, z, x, y, z) >= reach


@njit(cache=True, inline="always")
def _to_obstacle(world, i, k, scene):
    """Signed distance from ``world[i]`` to obstacle ``k`` of an unpack_scene tuple."""
    box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, _ = scene
    return obstacle_distance(world[i, 0], world[i, 1], world[i, 2], k, box_c, box_r, box_h, sph_c, sph_r, cyl_c,
                             cyl_a, cyl_h, cyl_r)  # fmt: skip


@njit(cache=True, inline="always")
def _group_vs_obstacle(g, k, robot, scene, work, stop_at_touch):
    """Group ``g`` against obstacle ``k``, whose bounds meet: 0 its outer spheres clear the obstacle, 1 some touch
    it, 2 an inner ball hits it and it is exact (or, with ``stop_at_touch``, an outer sphere touches it: the answer
    is then decided)."""
    (_, _, _, _, _, _, s_joint, s_center, s_radius, s_inner, _, _, _, _, _, padding,
     c_start, c_joint, c_center, c_radius, g_clusters) = robot  # fmt: skip
    rot, pos, _, cworld, sworld, clusters_placed, spheres_placed, bounds = work
    exact = scene[9]
    place_members(g, g_clusters, clusters_placed, rot, pos, c_joint, c_center, cworld)
    touched = 0
    for c in range(g_clusters[g], g_clusters[g + 1]):
        reach = c_radius[c] + padding
        if _beyond(cworld, c, reach, bounds, k) or _to_obstacle(cworld, c, k, scene) >= reach:
            continue
        place_members(c, c_start, spheres_placed, rot, pos, s_joint, s_center, sworld)
        for s in range(c_start[c], c_start[c + 1]):
            d = _to_obstacle(sworld, s, k, scene)
            if (exact[k] and d < s_inner[s] + padding) or (stop_at_touch and d < s_radius[s] + padding):
                return 2
            if d < s_radius[s] + padding:
                touched = 1
    return touched


@njit(cache=True, inline="always")
def _pair_vs_pair(ga, gb, robot, work, stop_at_touch):
    """Self-collision pair (ga, gb), whose groups' bounds meet, as _group_vs_obstacle answers: 0 clear, 1 outer
    spheres touch, 2 inner balls hit (or outer spheres touch, with ``stop_at_touch``)."""
    (_, _, _, _, _, _, s_joint, s_center, s_radius, s_inner, _, _, _, g_radius, _, padding,
     c_start, c_joint, c_center, c_radius, g_clusters) = robot  # fmt: skip
    rot, pos, gworld, cworld, sworld, clusters_placed, spheres_placed, _ = work
    place_members(ga, g_clusters, clusters_placed, rot, pos, c_joint, c_center, cworld)
    place_members(gb, g_clusters, clusters_placed, rot, pos, c_joint, c_center, cworld)
    touched = 0
    for ca in range(g_clusters[ga], g_clusters[ga + 1]):
        if row_distance(cworld, ca, gworld, gb) >= c_radius[ca] + g_radius[gb] + padding:
            continue
        for cb in range(g_clusters[gb], g_clusters[gb + 1]):
            if row_distance(cworld, ca, cworld, cb) >= c_radius[ca] + c_radius[cb] + padding:
                continue
            place_members(ca, c_start, spheres_placed, rot, pos, s_joint, s_center, sworld)
            place_members(cb, c_start, spheres_placed, rot, pos, s_joint, s_center, sworld)
            for sa in range(c_start[ca], c_start[ca + 1]):
                if row_distance(sworld, sa, cworld, cb) >= s_radius[sa] + c_radius[cb] + padding:
                    continue
                for sb in range(c_start[cb], c_start[cb + 1]):
                    d = row_distance(sworld, sa, sworld, sb)
                    if d < s_inner[sa] + s_inner[sb] + padding or (
                        stop_at_touch and d < s_radius[sa] + s_radius[sb] + padding
                    ):
                        return 2
                    if d < s_radius[sa] + s_radius[sb] + padding:
                        touched = 1
    return touched


@njit(cache=True, inline="always")
def _vs_scene(robot, scene, work, stop_at_touch):
    """Every moving group against every obstacle, answered like :func:`_group_vs_obstacle`.

    The groups' bound test stays in this loop: inside the inlined helper, numba's reference counting of the
    helper's array arguments made every (group, obstacle) test cost as much as the spheres'.
    """
    g_joint, g_radius, padding = robot[11], robot[13], robot[15]  # unpack_robot's order
    gworld, bounds = work[2], work[7]
    lo0 = lo1 = lo2 = np.inf  # the moving groups' bounds, padded: an obstacle beyond this box is beyond all of them
    hi0 = hi1 = hi2 = -np.inf
    for g in range(g_joint.shape[0]):
        if g_joint[g] != 0:
            reach = g_radius[g] + padding
            lo0, hi0 = min(lo0, gworld[g, 0] - reach), max(hi0, gworld[g, 0] + reach)
            lo1, hi1 = min(lo1, gworld[g, 1] - reach), max(hi1, gworld[g, 1] + reach)
            lo2, hi2 = min(lo2, gworld[g, 2] - reach), max(hi2, gworld[g, 2] + reach)
    touched = 0
    for k in range(bounds.shape[0]):
        if _box_gap(bounds, k, lo0, lo1, lo2, hi0, hi1, hi2) >= 0.0:
            continue
        for g in range(g_joint.shape[0]):
            if g_joint[g] == 0:  # fixed to the world: like the exact checker, never tested against the scene
                continue
            reach = g_radius[g] + padding
            if _beyond(gworld, g, reach, bounds, k) or _to_obstacle(gworld, g, k, scene) >= reach:
                continue
            hit = _group_vs_obstacle(g, k, robot, scene, work, stop_at_touch)
            if hit == 2:
                return 2
            touched |= hit
    return touched


@njit(cache=True, inline="always")
def _vs_self(robot, work, stop_at_touch):
    """Every self-collision pair, answered like :func:`_pair_vs_pair` (its groups' bound test here, as in
    :func:`_vs_scene`)."""
    g_radius, self_pairs, padding = robot[13], robot[14], robot[15]
    gworld = work[2]
    touched = 0
    for p in range(self_pairs.shape[0]):
        ga, gb = self_pairs[p, 0], self_pairs[p, 1]
        if row_distance(gworld, ga, gworld, gb) >= g_radius[ga] + g_radius[gb] + padding:
            continue
        hit = _pair_vs_pair(ga, gb, robot, work, stop_at_touch)
        if hit == 2:
            return 2
        touched |= hit
    return touched


@njit(cache=True, inline="always")
def _place_state(q, robot, work):
    """``work``'s joint poses and group centres for full configuration ``q``, no cluster or sphere placed yet."""
    parent, kind, axis, prot, ppos, idx_q = robot[:6]
    rot, pos, gworld, _, _, clusters_placed, spheres_placed, _ = work
    joint_poses_nb(q, parent, kind, axis, prot, ppos, idx_q, rot, pos)
    place_points(rot, pos, robot[11], robot[12], 0, robot[11].shape[0], gworld)
    clusters_placed[:] = False
    spheres_placed[:] = False


@njit(cache=True, inline="always")
def classify(q, robot, scene, work, stop_at_touch):
    """VALID, COLLIDING or AMBIGUOUS for one full configuration: the answer of the sphere checker's
    classify_state without a grid, computed in a tight loop down the bounding hierarchy. Every group's
    bound is placed once; a group's clusters only when its bound reaches an obstacle or the other group
    of a self-collision pair, a cluster's spheres only when its bound does, each at most once per state.
    ``stop_at_touch``: AMBIGUOUS counts as COLLIDING (the pure sphere model), so the first outer sphere
    that touches ends the test.

    ``robot``/``scene``: unpack_robot/unpack_scene tuples; ``work``: :func:`work_arrays`. Inlined into its
    caller's loop: a call per state, with these tuples as arguments, cost about a third of a microsecond.
    """
    _place_state(q, robot, work)
    scene_hit = _vs_scene(robot, scene, work, stop_at_touch)
    if scene_hit == 2:
        return COLLIDING
    self_hit = _vs_self(robot, work, stop_at_touch)
    if self_hit == 2:
        return COLLIDING
    return AMBIGUOUS if scene_hit or self_hit else VALID


@njit(cache=True, inline="always")
def _apart_on_shapes(a, b, obstacle, robot, scene, work, shapes, records):
    """Whether GJK's lower bound (``support_bounds``) keeps group ``a``'s exact shape farther than the padding from
    obstacle ``b``'s primitive (which contains the obstacle) or, not ``obstacle``, from group ``b``'s shape, at the
    poses in ``work``; False without a shape (``shapes``: the robot's records; ``records``: two work records)."""
    g_joint, padding = robot[11], robot[15]
    rot, pos, gworld = work[0], work[1], work[2]
    s_kind, s_rot, s_pos, s_size, s_start, verts = shapes
    kinds, cs, rs, ss, vr = records
    if s_kind[a] == NO_SHAPE or (not obstacle and s_kind[b] == NO_SHAPE):
        return False
    place_shape(a, rot[g_joint[a]], pos[g_joint[a]], s_kind, s_rot, s_pos, s_size, s_start, 0, kinds, cs, rs, ss, vr)
    if obstacle:
        box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, _ = scene
        load_primitive(b, box_c, box_r, box_h, sph_c, sph_r, cyl_c, cyl_a, cyl_h, cyl_r, 1, kinds, cs, rs, ss)
    else:
        place_shape(b, rot[g_joint[b]], pos[g_joint[b]], s_kind, s_rot, s_pos, s_size, s_start, 1, kinds, cs, rs, ss,
                    vr)  # fmt: skip
    return convex_bound(kinds, cs, rs, ss, vr, verts, padding + CLEAR_BY, gworld[a]) > padding


@njit(cache=True)
def clear_on_shapes(q, robot, scene, work, shapes):
    """Whether every pair of full configuration ``q`` that the sphere model leaves in doubt (outer spheres within
    the padding, no inner ball hit) is :func:`_apart_on_shapes`: then coal would find no contact either (a mesh's
    hull contains it, an obstacle's primitive the obstacle). The pairs are found as :func:`classify` finds them;
    False at the first one not proven apart. Rewrites ``work`` for ``q``."""
    g_joint, g_radius, self_pairs, padding = robot[11], robot[13], robot[14], robot[15]
    _place_state(q, robot, work)
    gworld, records = work[2], new_records()
    n_obstacles = scene[0].shape[0] + scene[3].shape[0] + scene[5].shape[0]
    for g in range(g_joint.shape[0]):
        if g_joint[g] == 0:  # fixed to the world: never tested against the scene
            continue
        for k in range(n_obstacles):
            if _to_obstacle(gworld, g, k, scene) >= g_radius[g] + padding:
                continue
            touch = _group_vs_obstacle(g, k, robot, scene, work, False)
            if touch == 2 or (touch == 1 and not _apart_on_shapes(g, k, True, robot, scene, work, shapes, records)):
                return False
    for p in range(self_pairs.shape[0]):
        a, b = self_pairs[p, 0], self_pairs[p, 1]
        if row_distance(gworld, a, gworld, b) >= g_radius[a] + g_radius[b] + padding:
            continue
        touch = _pair_vs_pair(a, b, robot, work, False)
        if touch == 2 or (touch == 1 and not _apart_on_shapes(a, b, False, robot, scene, work, shapes, records)):
            return False
    return True


@njit(cache=True)
def pairs_clear_on_shapes(q, pairs, robot, scene, work, shapes):
    """:func:`clear_on_shapes` of the pairs a scan listed in doubt at ``q`` (``scan_nb``'s ``amb``: kind 0 a group
    and an obstacle, 1 two groups)."""
    _place_state(q, robot, work)
    records = new_records()
    for i in range(pairs.shape[0]):
        if not _apart_on_shapes(pairs[i, 1], pairs[i, 2], pairs[i, 0] == 0, robot, scene, work, shapes, records):
            return False
    return True


@njit(cache=True)
def _near_roots(q, indices, roots, exact_near):
    """Whether full configuration ``q`` is within ``exact_near`` (L∞ over the group's ``indices``) of a root."""
    for r in range(2):
        far = 0.0
        for a in range(indices.shape[0]):
            far = max(far, abs(q[indices[a]] - roots[r, a]))
        if far <= exact_near:
            return True
    return False


@njit(cache=True)
def check_edge(
    qa, qb, resolution, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states, st, roots,
    exact_near,
):
    """VALID, COLLIDING or AMBIGUOUS for the edge qa → qb (qa excluded) on the sphere model.

    The edge's states, as full configurations (``base`` supplies the joints outside the group's
    ``indices``), are classified in bisection order: by :func:`classify` on the sphere checker's
    packed robot and scene (``ri``/``rf``/``sf``), or, when the checker looks obstacles up in a grid
    (a large scene, ``grid_i``/``grid_f``), by its own scan (``scan_nb`` with its work arrays
    ``amb``/``mark``). COLLIDING at the first colliding state. With ``confirm``, states that are only
    ambiguous and within ``exact_near`` (L∞) of one of the ``roots`` (start, goal) are decided on the exact
    shapes: valid where GJK's bounds clear every pair near contact (:func:`clear_on_shapes`, ``shapes``), else
    copied to ``amb_states`` (``st[N_AMB]`` of them) for coal, with every later one (coal is asked anyway, and most
    such states are contacts: GJK's time would be lost), and the edge is AMBIGUOUS if no state collides;
    other ambiguous states collide (the pure, conservative sphere model, everywhere without ``confirm``).
    """
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    order, queue = edge_buffers(1)
    return edge_status(qa, qb, resolution, base, indices, robot, scene, work_arrays(robot, scene), order, queue,
                       np.empty(base.shape[0]), ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states,
                       st, roots, exact_near)  # fmt: skip


@njit(cache=True)
def edge_status(qa, qb, resolution, base, indices, robot, scene, work, order, queue, q, ri, rf, sf, grid_i, grid_f,
                amb, mark, shapes, confirm, amb_states, st, roots, exact_near):  # fmt: skip
    """:func:`check_edge` on the robot and scene its caller unpacked once (:func:`run`, the shortcut kernel of
    :mod:`~maru_planner.planning.compiled_shortcut`), their :func:`work_arrays`, edge buffers (:func:`edge_buffers`;
    larger ones are made for a longer edge) and a configuration buffer ``q``.

    Without a grid each state is made when its turn comes: most edges of a search end at their first states.
    """
    dim = qa.shape[0]
    steps = 0.0
    for a in range(dim):
        steps = max(steps, abs(qb[a] - qa[a]))
    n = max(1, int(np.ceil(steps / resolution)))
    if order.shape[0] < n:
        order, queue = edge_buffers(n)
    _bisection_order_into(n, order, queue)
    if grid_i[0] > 0:
        return _check_edge_by_grid(qa, qb, n, order, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes,
                                   confirm, amb_states, st, roots, exact_near, robot, scene, work)  # fmt: skip
    n_amb = 0
    for row in range(n):
        t = (order[row] + 1) / n  # the state written out as in _check_edge_by_grid: a shared helper cost 2-3 %
        q[:] = base
        for a in range(dim):
            q[indices[a]] = qa[a] + t * (qb[a] - qa[a])
        exact = confirm and _near_roots(q, indices, roots, exact_near)
        status = classify(q, robot, scene, work, not exact)
        st[CHECKS] += 1
        if status == COLLIDING or (status == AMBIGUOUS and not exact):
            return COLLIDING
        if status == AMBIGUOUS and (n_amb > 0 or not clear_on_shapes(q, robot, scene, work, shapes)):
            for a in range(dim):
                amb_states[n_amb, a] = q[indices[a]]
            n_amb += 1
    st[N_AMB] = n_amb
    return AMBIGUOUS if n_amb > 0 else VALID


@njit(cache=True)
def _check_edge_by_grid(qa, qb, n, order, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm,
                        amb_states, st, roots, exact_near, robot, scene, work):  # fmt: skip
    """:func:`check_edge` of an edge of ``n`` states in ``order`` through the checker's grid scan (``scan_nb``)."""
    dim = qa.shape[0]
    states = np.empty((n, base.shape[0]))
    for r in range(n):
        t = (order[r] + 1) / n
        states[r] = base
        for a in range(dim):
            states[r, indices[a]] = qa[a] + t * (qb[a] - qa[a])
    n_amb, row = 0, 0
    while row < n:
        hit, status, n_pairs = scan_nb(states, row, ri, rf, sf, grid_i, grid_f, amb, mark, True)
        if hit < 0:
            st[CHECKS] += n - row
            break
        st[CHECKS] += hit + 1 - row
        row = hit + 1
        if status == AMBIGUOUS and not (confirm and _near_roots(states[hit], indices, roots, exact_near)):
            status = COLLIDING
        if status == COLLIDING:
            return COLLIDING
        in_doubt = amb[:n_pairs]
        if status == AMBIGUOUS and (n_amb > 0 or not pairs_clear_on_shapes(states[hit], in_doubt, robot, scene, work,
                                                                         shapes)):  # fmt: skip
            for a in range(dim):
                amb_states[n_amb, a] = states[hit, indices[a]]
            n_amb += 1
    st[N_AMB] = n_amb
    return AMBIGUOUS if n_amb > 0 else VALID


@njit(cache=True)
def _add(nodes, parent, st, tree, q, par):
    field = N0 + tree
    i = st[field]
    nodes[tree, i] = q
    parent[tree, i] = par
    st[field] = i + 1
    return i


@njit(cache=True)
def _solved(st, tree, node, other):
    """The trees meet: ``node`` of ``tree`` and ``other`` of the other tree."""
    st[LINK0 + tree] = node
    st[LINK0 + 1 - tree] = other
    return SOLVED


@njit(cache=True)
def _propose(nodes, radius, st, q_new, lower, upper, rng, max_range):
    """The next edge: from node st[FROM] of tree st[TREE] to ``q_new`` (st[REACHED]: q_new is the target).

    False, and no edge, when an extension's sample lies outside its nearest node's dynamic domain (``radius``).
    """
    phase, tree = st[PHASE], st[TREE]
    if phase == DIRECT:
        q_new[:] = nodes[1, 0]
        st[TREE], st[FROM], st[REACHED] = 0, 0, 1
        return True
    if phase == EXTEND:
        sample = np.empty(lower.shape[0])
        for a in range(lower.shape[0]):
            sample[a] = lower[a] + uniform(rng) * (upper[a] - lower[a])
        nearest, distance = _nearest_with_distance(nodes[tree], st[N0 + tree], sample)
        if distance > radius[tree, nearest]:
            return False
        st[FROM] = nearest
        st[REACHED] = _steer(nodes[tree, nearest], sample, max_range, q_new)
        return True
    st[REACHED] = _steer(nodes[tree, st[FROM]], nodes[1 - tree, st[TARGET]], max_range, q_new)
    return True


@njit(cache=True)
def _next_extension(st, last, tuning):
    """The tree to extend after tree ``last``'s round: the other one (as OMPL), unless balancing keeps
    extending ``last`` while the other has at least twice its nodes (VAMP's ``balance``, ``tree_ratio`` 1)."""
    other = 1 - last
    if tuning[BALANCE] > 0.0 and st[N0 + other] >= 2 * st[N0 + last]:
        return last
    return other


@njit(cache=True)
def _update_domain(radius, tree, node, valid, tuning):
    """Dynamic domain (Yershova et al. 2005, as VAMP): a node whose extension failed gets a domain of
    ``DOMAIN_RADIUS``, shrunk by ``DOMAIN_ALPHA`` at each further failure (not below ``DOMAIN_MIN_RADIUS``)
    and grown by it at each success."""
    if tuning[DOMAIN_RADIUS] <= 0.0:
        return
    r = radius[tree, node]
    if valid:
        if r < np.inf:
            radius[tree, node] = r * (1.0 + tuning[DOMAIN_ALPHA])
    elif r == np.inf:
        radius[tree, node] = tuning[DOMAIN_RADIUS]
    else:
        radius[tree, node] = max(r * (1.0 - tuning[DOMAIN_ALPHA]), tuning[DOMAIN_MIN_RADIUS])


@njit(cache=True)
def _apply(nodes, parent, radius, st, q_new, valid, tuning):
    """Update the trees and the phase with the verdict on the proposed edge; SOLVED or RUNNING."""
    phase, tree = st[PHASE], st[TREE]
    if phase == DIRECT:
        if valid:
            st[DUPLICATE] = 0
            return _solved(st, 0, 0, 0)
        st[PHASE], st[TREE] = EXTEND, 0
        return RUNNING
    if phase == EXTEND:
        _update_domain(radius, tree, st[FROM], valid, tuning)
    if not valid:  # trapped: the round of the tree that extended last is over
        st[PHASE], st[TREE] = EXTEND, _next_extension(st, tree if phase == EXTEND else 1 - tree, tuning)
        return RUNNING
    new = _add(nodes, parent, st, tree, q_new, st[FROM])
    radius[tree, new] = np.inf
    if phase == EXTEND:
        other = 1 - tree
        st[PHASE], st[TREE], st[TARGET] = CONNECT, other, new
        st[FROM] = _nearest(nodes[other], st[N0 + other], q_new)
        return RUNNING
    if st[REACHED]:
        st[DUPLICATE] = 1
        return _solved(st, tree, new, st[TARGET])
    st[FROM] = new
    return RUNNING


@njit(cache=True)
def run(nodes, parent, radius, verdict, max_edges, st, q_new, amb_states, tuning, lower, upper, rng, max_range,
        resolution, base, indices, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, exact_near):  # fmt: skip
    """Advance the search by at most ``max_edges`` edge checks; SOLVED, RUNNING, NEED_EXACT or FULL (module doc).

    ``verdict``: the exact answer for the pending edge after a NEED_EXACT return (ignored otherwise);
    ``tuning``: :func:`tuning`; ``ri`` … ``shapes``: the sphere checker's kernel inputs; ``exact_near``: see
    :func:`check_edge`.
    """
    if st[PENDING]:
        st[PENDING] = 0
        if _apply(nodes, parent, radius, st, q_new, verdict, tuning) == SOLVED:
            return SOLVED
    cap = nodes.shape[1]
    robot, scene = unpack_robot(ri, rf), unpack_scene(sf)
    work = work_arrays(robot, scene)
    longest = min(max_range, np.max(upper - lower))  # an extension's edge: L∞ <= its L2 range, within the bounds
    order, queue = edge_buffers(int(np.ceil(longest / resolution)) + 1)
    q = np.empty(base.shape[0])
    for _ in range(max_edges):
        if st[N0] >= cap or st[N1] >= cap:
            return FULL
        if not _propose(nodes, radius, st, q_new, lower, upper, rng, max_range):  # an iteration without an edge
            st[TREE] = _next_extension(st, st[TREE], tuning)
            continue
        tree = st[TREE]
        status = edge_status(nodes[tree, st[FROM]], q_new, resolution, base, indices, robot, scene, work, order,
                             queue, q, ri, rf, sf, grid_i, grid_f, amb, mark, shapes, confirm, amb_states, st,
                             nodes[:, 0], exact_near)  # fmt: skip
        if status == AMBIGUOUS:
            st[PENDING] = 1
            return NEED_EXACT
        if _apply(nodes, parent, radius, st, q_new, status == VALID, tuning) == SOLVED:
            return SOLVED
    return RUNNING


@njit(cache=True)
def solution_path(nodes, parent, st):
    """Waypoints start → goal of a SOLVED search: tree 0's branch to LINK0, then tree 1's from LINK1."""
    n0 = 0
    i = st[LINK0]
    while i >= 0:
        n0 += 1
        i = parent[0, i]
    first = parent[1, st[LINK1]] if st[DUPLICATE] else st[LINK1]
    n1 = 0
    i = first
    while i >= 0:
        n1 += 1
        i = parent[1, i]
    out = np.empty((n0 + n1, nodes.shape[2]))
    i, k = st[LINK0], n0 - 1
    while i >= 0:
        out[k] = nodes[0, i]
        i, k = parent[0, i], k - 1
    i, k = first, n0
    while i >= 0:
        out[k] = nodes[1, i]
        i, k = parent[1, i], k + 1
    return out
