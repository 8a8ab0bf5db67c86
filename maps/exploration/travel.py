"""Travel cost G(v_S, P_b) of eq. 1 through the exploration map's known free space.

G is the 8-connected grid shortest path (Dijkstra from ``scipy.sparse.csgraph``, step costs
``res`` and ``res * sqrt 2``) through *known* free space whose clearance to the nearest obstacle
cell exceeds the robot radius (the map's ``clearance``, from
``scipy.ndimage.distance_transform_edt``). Unknown cells are not traversed but do not inflate: a
border next to the unknown must be reachable. The robot's trail (``visited``) is always
traversable: it fitted there, and new obstacle evidence (a squeeze narrowed by stereo noise) must
not lock it in a pocket of the map, which would read as "no border reachable", i.e. done. A robot
standing on a cell that is not traversable starts from the nearest traversable cell within one
radius, the snap added to every cost. Optionally, steps near obstacles cost more (``margin``,
``penalty``), so that paths keep off walls where there is room.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from maps.exploration.grid import Cell, ExplorationMap, GridFrame, read_only


@dataclass(frozen=True, slots=True)
class TravelCost:
    """Shortest travel through known free space from one start (``G(v_S, .)`` of eq. 1).

    ``cost``: metres to every cell of the map's grid (inf: unreachable); ``previous``: the flat
    index of the previous cell on the shortest path (-1 at the start and where unreachable).
    """

    frame: GridFrame
    cost: np.ndarray
    previous: np.ndarray

    def at(self, xy: np.ndarray) -> np.ndarray:
        """G to each (x, y) (inf outside the grid)."""
        return self.frame.sample(self.cost, xy, np.inf)

    def path_to(self, xy: tuple[float, float]) -> np.ndarray:
        """Cell centres (K x 2) from the start to the cell of ``xy``; empty when unreachable."""
        rows, cols = self.frame.cell_of(np.array([xy]))
        if not self.frame.inside(rows, cols)[0] or not np.isfinite(self.cost[rows[0], cols[0]]):
            return np.zeros((0, 2))
        flat = int(rows[0] * self.frame.cols + cols[0])
        r, c = np.divmod(chain_to(self.previous.ravel(), flat), self.frame.cols)
        return self.frame.centre_of(r, c)


def traversable(m: ExplorationMap, robot_radius: float) -> np.ndarray:
    """Known free cells whose clearance to the nearest obstacle cell exceeds ``robot_radius``, and
    the robot's trail (``visited``: it fitted there)."""
    return ((m.cells == Cell.FREE) & (m.clearance > robot_radius)) | m.visited


def travel_cost(
    m: ExplorationMap,
    start: tuple[float, float],
    robot_radius: float,
    *,
    margin: float = 0.0,
    penalty: float = 0.0,
    crossing: float = math.inf,
    closed: np.ndarray | None = None,
) -> TravelCost:
    """G from ``start`` to every cell: 8-connected Dijkstra over :func:`traversable` cells.

    Steps cost their length; with ``margin`` > 0, a step between cells with less clearance than
    ``robot_radius + margin`` costs up to ``1 + penalty`` times its length (a linear ramp, like a
    costmap's inflation), so that paths keep off obstacles where there is room and G counts the
    care a squeeze takes. Without (the default), G is the path length in metres.

    With a finite ``crossing``, the *known* cells the robot's disc cannot pass (obstacle cells, and
    free cells too near them) are traversed as well, a step into one costing ``crossing`` times
    the length (never the unknown, nor the ``closed`` cells, a bool grid): the path that crosses
    the least of what closes the way, for looking at it again
    (:func:`maps.exploration.goal.verification_goal`). It is no path to drive.
    """
    frame = m.frame
    cost = np.full(frame.shape, np.inf)
    previous = np.full(frame.shape, -1, dtype=np.int64)
    room = m.clearance
    ok = ((m.cells == Cell.FREE) & (room > robot_radius)) | m.visited
    across = np.zeros(frame.shape, dtype=bool)
    if math.isfinite(crossing):
        across = (m.cells != Cell.UNKNOWN) & ~ok & (True if closed is None else ~closed)
    source = _snap(ok, frame, start, robot_radius)
    ok = ok | across
    if source is None:
        return TravelCost(frame, read_only(cost), read_only(previous))
    (sr, sc), snap = source
    rows, cols = np.nonzero(ok)
    box = (slice(rows.min(), rows.max() + 1), slice(cols.min(), cols.max() + 1))  # Dijkstra on the bounding box
    r0, c0 = box[0].start, box[1].start
    sub = ok[box]
    weight = np.ones(sub.shape)
    if margin > 0.0:
        weight += penalty * np.clip((robot_radius + margin - room[box]) / margin, 0.0, 1.0)
    weight[across[box]] = crossing
    node = np.full(sub.shape, -1, dtype=np.int64)
    node[sub] = np.arange(np.count_nonzero(sub))
    graph = grid_graph(sub, node, weight, frame.resolution)
    dist, pred = dijkstra(graph, directed=False, indices=int(node[sr - r0, sc - c0]), return_predecessors=True)
    sub_rows, sub_cols = np.nonzero(sub)
    cost[sub_rows + r0, sub_cols + c0] = dist + snap
    has_pred = pred >= 0
    pred_rows, pred_cols = sub_rows[np.maximum(pred, 0)] + r0, sub_cols[np.maximum(pred, 0)] + c0
    previous[sub_rows + r0, sub_cols + c0] = np.where(has_pred, pred_rows * frame.cols + pred_cols, -1)
    return TravelCost(frame, read_only(cost), read_only(previous))


def _snap(
    ok: np.ndarray, frame: GridFrame, start: tuple[float, float], radius: float
) -> tuple[tuple[int, int], float] | None:
    """The start cell if traversable, else the nearest traversable cell within ``radius`` (and how far)."""
    rows, cols = frame.cell_of(np.array([start]))
    r, c = int(rows[0]), int(cols[0])
    if frame.inside(rows, cols)[0] and ok[r, c]:
        return (r, c), 0.0
    k = int(math.ceil(radius / frame.resolution)) + 1
    r0, c0 = max(r - k, 0), max(c - k, 0)
    window = ok[r0 : max(r + k + 1, 0), c0 : max(c + k + 1, 0)]
    wr, wc = np.nonzero(window)
    if len(wr) == 0:
        return None
    d = np.hypot(*(frame.centre_of(wr + r0, wc + c0) - np.asarray(start)).T)
    best = int(np.argmin(d))
    if d[best] > radius + frame.resolution:
        return None
    return (int(wr[best] + r0), int(wc[best] + c0)), float(d[best])


def chain_to(previous: np.ndarray, end: int) -> np.ndarray:
    """The indices from the start to ``end`` along a Dijkstra's predecessors (``previous``: -1 at the
    start)."""
    chain = [end]
    while previous[chain[-1]] >= 0:
        chain.append(int(previous[chain[-1]]))
    return np.asarray(chain[::-1])


def grid_graph(ok: np.ndarray, node: np.ndarray, weight: np.ndarray, res: float) -> coo_matrix:
    """The 8-connected graph of the ``ok`` cells (undirected: each pair once): step length times the
    mean ``weight`` of its two cells."""
    heads, tails, weights = [], [], []
    rows, cols = ok.shape
    for dr, dc, length in ((0, 1, res), (1, 0, res), (1, 1, res * math.sqrt(2.0)), (1, -1, res * math.sqrt(2.0))):
        a = (slice(0, rows - dr), slice(max(0, -dc), cols - max(0, dc)))
        b = (slice(dr, rows), slice(max(0, dc), cols - max(0, -dc)))
        both = ok[a] & ok[b]
        heads.append(node[a][both])
        tails.append(node[b][both])
        weights.append(length * (weight[a][both] + weight[b][both]) / 2.0)
    n = int(ok.sum())
    return coo_matrix((np.concatenate(weights), (np.concatenate(heads), np.concatenate(tails))), shape=(n, n)).tocsr()
