"""Frame-to-frame tracking of the marked body, head to feet (Pan, Zhuang and Liu 2000, "Feature tracking"): morph
blocks matched to frame-0 colours, the head started by image difference (Eq. 1-5), limbs found around roots."""

from __future__ import annotations

from collections import deque

import numpy as np

from mocap.body import JOINT_INDEX
from mocap.camera import Pinhole, default_camera
from mocap.image.edges import Edges
from mocap.person import Landmarks
from mocap.track import blocks
from mocap.track.blocks import THETA, M, N, X, Y, block_end, from_block, to_block
from mocap.track.headmotion import P_START, adapt_threshold, head_displacement
from mocap.track.landmarks import seed_marks
from mocap.track.limbs import (
    HEAD_COST,
    LEG_OUTLINE_COST,
    TWIN_COST,
    TWIN_OVERLAP,
    TrunkDepth,
    added,
    arm_limits_cost,
    around_root,
    leg_limits_cost,
    limb_cost,
    limb_penalty,
    outline_cost,
    settled_knee,
    twin_overlap,
)
from mocap.track.loss import DISTINCT, body_lost, part_confidence
from mocap.track.marks import body_scale
from mocap.track.opinion import landmark_block, limb_opinion, second_opinion, trunk_apart
from mocap.track.parts import (
    ARMS,
    HEAD,
    LEGS,
    LIMBS,
    PART_JOINTS,
    PARTS,
    TORSO,
    TWIN_PART,
    TWINS,
    arm_grids,
    far_forearm,
    mirrored_model,
    part_lengths,
    part_widths,
    same_clothes,
    search_part,
    skeleton,
)
from mocap.track.reacquire import carried, distinctness, reacquired, scan_heads

BEYOND = 0.3  # of a part's length: the block reaches this far past both joints
MAX_STRETCH = 1.15  # a part is seen at most this much longer than its length
UPDATE_RATE = 0.3  # linear weighting of a colour model by the new block
UPDATE_MIN = 0.9  # of the part's median S so far: worse matches leave the model
ANCHOR = 0.5  # weight of frame 0's colours in every updated model
HISTORY = 150  # frames of S that the median looks back on
USUAL_MIN = 0.6  # of a part's model length: the least usual length (around_root)
ZOOM_RANGE = (0.5, 2.0)  # of the marked head's length: the head's (the body's) scale stays in it
HEAD_RETRY = 0.3  # of the head's median S: a worse match is searched again (_track_head)
FAR_UPPER_WEIGHT = 0.3  # of its 1/S: what the far arm's upper arm's match weighs around its root
FAR_UPPER_SCALES = (1.0, 0.9)  # of its usual length: the far arm's upper arm's lengths tried there
ELSEWHERE = 2.0  # trunk radii (opinion.trunk_apart): landmarks this far off see the body elsewhere


class BodyTracker:
    """State carried between frames: blocks (10, 5) and velocities, colour models, recent S, the head's threshold p,
    the trunk in 3D (``TrunkDepth``; ``camera`` default the frame's) and the parts' confidence at ``fps``;
    ``guided``: a person model's landmarks come with the frames (``step``), finding a body the colours lose."""

    def __init__(
        self,
        frame0: np.ndarray,
        marks: np.ndarray,
        camera: Pinhole | None = None,
        turn: str | None = None,
        fps: float = 25.0,
        guided: bool = False,
    ):
        scale = body_scale(marks)
        self.fps, self.guided = fps, guided
        self.trunk = TrunkDepth(marks, camera or default_camera(frame0.shape[1], frame0.shape[0]), turn)
        self.limb_costs: dict[int, tuple[blocks.Penalty, blocks.Penalty]] = {}
        self.blocks = blocks.between(marks[PART_JOINTS[:, 0]], marks[PART_JOINTS[:, 1]], part_widths(marks, scale))
        self.longest = MAX_STRETCH * np.maximum(scale * part_lengths(), self.blocks[:, M])
        self.head_width = self.blocks[HEAD, N]
        self.head_lengths = np.array(ZOOM_RANGE) * self.blocks[HEAD, M]
        self.widths = np.outer(self.blocks[:, N], ZOOM_RANGE)
        # usual lengths (around_root): as marked, unless marked much foreshortened
        self.lengths = np.maximum(self.blocks[:, M], USUAL_MIN * self.longest / MAX_STRETCH)
        self.confidence = np.ones(len(PARTS))
        self.lost = self.held = False
        self.velocity = np.zeros_like(self.blocks)
        self.far_forearm = far_forearm(self.trunk.depths)
        self.grids = arm_grids(
            frame0,
            self.blocks,
            [blocks.make_grid(b[M], b[N], 0.0 if k == HEAD else BEYOND) for k, b in enumerate(self.blocks)],
            self.far_forearm,
        )
        self.models = [blocks.sample_blocks(frame0, b, g)[0] for b, g in zip(self.blocks, self.grids)]
        self.marked = list(self.models)
        self.good = self.blocks.copy()
        self.history: deque[np.ndarray] = deque(maxlen=HISTORY)
        self.chest = to_block(marks[JOINT_INDEX["chest"]], self.blocks[TORSO])
        self.p = P_START
        self.frame = frame0

    def step(self, frame: np.ndarray, seen: Landmarks | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Track the next frame (``seen``: the person model's landmarks there): its (16, 2) joints and (10,) S."""
        predicted = self._predicted()
        new, s = predicted.copy(), np.zeros(len(PARTS))
        new[HEAD], s[HEAD] = self._track_head(frame, predicted[HEAD])
        if seen is not None:
            second_opinion(HEAD, new, s, seen, lambda start: self._head_search(frame, start))
        predicted[TORSO, :2] = block_end(new[HEAD])
        new[TORSO], s[TORSO] = self._track_torso(frame, predicted[TORSO], new[HEAD])
        if seen is not None:
            zoom = self._zoom(new[HEAD])
            second_opinion(TORSO, new, s, seen, lambda start: self._search(frame, TORSO, start, zoom))
        refound = self.lost and self._reacquire(frame, new, s, seen)
        edges = Edges.of_frame(frame)
        new = self._limbs(frame, new, s, seen, edges)
        lost = self._judged_lost(frame, new, s, refound, seen)
        if lost and not self.lost and self.guided and self._reacquire(frame, new, s, seen, scan=False):
            new = self._limbs(frame, new, s, seen, edges)  # the landmarks find the body the colours just lost
            lost = self._judged_lost(frame, new, s, True, seen)
        self.lost = lost
        self._update(frame, new, s, self.lost)
        return skeleton(new, self.chest), s

    def _limbs(self, frame: np.ndarray, new: np.ndarray, s: np.ndarray, seen: Landmarks | None, edges: Edges):
        """``new`` with the limbs tracked from its head and trunk (the landmarks' second opinion where their trunk
        is the tracked one), kept sane; the parts' confidence taken."""
        self.limb_costs = self._limb_costs(new, edges)
        for k in LIMBS:
            self._track_limb(frame, new, s, k, self._avoided(k, new))
        for twins in TWINS:
            self._part_twins(frame, new, s, twins)
        if seen is not None and trunk_apart(seen, skeleton(new, self.chest), new[TORSO]) <= 1.0:
            for k in LIMBS:
                limb_opinion(k, new, s, seen, lambda lower, k=k: self._hung_from(frame, new, s, k, lower))
        new = self._bounded(new, frame.shape)
        self.confidence = self._confidence(new, s, frame.shape)
        return new

    def _judged_lost(
        self, frame: np.ndarray, new: np.ndarray, s: np.ndarray, refound: bool, seen: Landmarks | None
    ) -> bool:
        """Whether the body is lost on a frame tracked to ``new`` (``refound``: re-acquired): once lost, until
        re-acquired; a held (``_held``) frame is judged without the usual S, which a changed background lowers; a
        body held or re-acquired by colours alone is lost where the person model sees it elsewhere (``seen``)."""
        lost = self.lost and not refound or bool(body_lost(self.confidence, self.lost))
        doubtful = refound or lost
        self.held = lost and self._held(frame, new)
        if self.held:
            self.confidence = self._confidence(new, s, frame.shape, np.full(len(PARTS), np.inf))
            lost = bool(body_lost(self.confidence))
        return lost or doubtful and self._contradicted(new, seen)

    def _contradicted(self, new: np.ndarray, seen: Landmarks | None) -> bool:
        """Whether the person model is sure of a body (landmarks.seed_marks) whose trunk is not ``new``'s."""
        if seen is None or seed_marks(seen, self.frame.shape) is None:
            return False
        return trunk_apart(seen, skeleton(new, self.chest), new[TORSO]) > ELSEWHERE

    def dressed_alike(self, frame: np.ndarray, marks: np.ndarray) -> bool:
        """Whether the body ``marks`` (16, 2) place on ``frame`` wears the marked body's clothes (parts.same_clothes
        of the trunk). A person model sure of a body can be sure of one it makes of the background."""
        width = part_widths(marks, body_scale(marks))[TORSO]
        trunk = blocks.between(marks[PART_JOINTS[[TORSO], 0]], marks[PART_JOINTS[[TORSO], 1]], width)
        seen = blocks.sample_blocks(frame, trunk, self.grids[TORSO])[0]
        return same_clothes(self.marked[TORSO], seen, self.grids[TORSO])

    def _held(self, frame: np.ndarray, new: np.ndarray) -> bool:
        """Whether head and trunk of ``new`` each match DISTINCT times better where they lie than anywhere else."""
        return all(distinctness(frame, self._model(k), self.grids[k], new[k]) >= DISTINCT for k in (HEAD, TORSO))

    def _reacquire(
        self, frame: np.ndarray, new: np.ndarray, s: np.ndarray, seen: Landmarks | None, scan: bool = True
    ) -> bool:
        """Whether a lost body's head and trunk are found again (into ``new``, ``s``; limbs from the good pose): from
        the landmarks' (``seen``) and, with ``scan``, the last head, the good one and the scan's."""
        shown = [None if seen is None else landmark_block(seen, k, self.good[k, N]) for k in (HEAD, TORSO)]
        starts = [b[None] for b in shown[:1] if b is not None]
        if scan:
            starts += [
                new[[HEAD]],
                self.good[[HEAD]],
                scan_heads(frame, self._model(HEAD), self.grids[HEAD], self.good[HEAD]),
            ]
        if not starts:
            return False
        trunks = None if shown[1] is None else shown[1][None]
        found = reacquired(
            frame,
            np.concatenate(starts),
            self.good,
            self._usual(),
            self._head_search,
            self._track_torso,
            self._score,
            trunks,
        )
        if found is None:
            return False
        self.blocks = carried(self.good, found.blocks[1])
        self.blocks[[HEAD, TORSO]] = found.blocks
        self.velocity[:] = 0.0
        new[:] = self.blocks
        s[[HEAD, TORSO]] = found.s
        return True

    def _score(self, frame: np.ndarray, k: int, candidates: np.ndarray) -> np.ndarray:
        """(K,) part k's S of blocks ``candidates`` (K, 5) where they lie."""
        return blocks.score(frame, self._model(k), self.grids[k], candidates)

    def _head_search(self, frame: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, float]:
        """The head's block and S searched from ``start``, its length within ZOOM_RANGE."""
        found, s = self._search(frame, HEAD, start, self._zoom(start))
        found[M] = np.clip(found[M], *self.head_lengths)
        return found, s

    def _confidence(self, new: np.ndarray, s: np.ndarray, shape: tuple, usual: np.ndarray | None = None) -> np.ndarray:
        """(10,) part confidences (loss.part_confidence) against ``usual`` S (default ``_usual``)."""
        expected = self.longest / MAX_STRETCH * new[HEAD, N] / self.head_width
        usual = self._usual() if usual is None else usual
        return part_confidence(new, self.blocks, s, usual, expected, shape, self.fps)

    def _bounded(self, new: np.ndarray, shape: tuple) -> np.ndarray:
        """Blocks kept sane: starts in the frame, sizes within ZOOM_RANGE, non-finite values from the last frame."""
        new = np.where(np.isfinite(new), new, self.blocks)
        new[:, X] = np.clip(new[:, X], 0, shape[1] - 1)
        new[:, Y] = np.clip(new[:, Y], 0, shape[0] - 1)
        new[:, N] = np.clip(new[:, N], self.widths[:, 0], self.widths[:, 1])
        new[:, M] = np.clip(new[:, M], 2.0, ZOOM_RANGE[1] * self.longest)
        return new

    def _predicted(self) -> np.ndarray:
        """Every block moved as over the last frame (constant velocity); widths follow the head's zoom."""
        predicted = self.blocks + self.velocity
        predicted[:, M] = np.maximum(predicted[:, M], 2.0)
        predicted[HEAD, M] = np.clip(predicted[HEAD, M], *self.head_lengths)
        predicted[1:, N] = self.blocks[1:, N] * predicted[HEAD, M] / self.blocks[HEAD, M]
        return predicted

    def _search(self, image: np.ndarray, k: int, start: np.ndarray, zoom: float, penalty: blocks.Penalty | None = None):
        """Part k's block and S searched from ``start`` (parts.search_part), the body at ``zoom``."""
        return search_part(image, self._model(k), self.grids[k], start, PARTS[k], self.longest[k] * zoom, penalty)

    def _zoom(self, head: np.ndarray) -> float:
        """The body's scale on a frame against the marks' by its ``head`` block."""
        return float(head[N] / self.head_width)

    def _track_head(self, frame: np.ndarray, predicted: np.ndarray) -> tuple[np.ndarray, float]:
        """The head block searched from the better-matching of the image difference's and constant velocity's
        calvaria, from the other too where S < HEAD_RETRY of usual; then p adapts."""
        head = self.blocks[HEAD]
        moved = head_displacement(self.frame, frame, head[:2], block_end(head), self.p)
        starts = np.stack([np.r_[head[:2] + moved.vector, predicted[2:]], predicted])
        order = np.argsort(-blocks.score(frame, self.models[HEAD], self.grids[HEAD], starts))
        found, s = self._search(frame, HEAD, starts[order[0]], self._zoom(head))
        if s < HEAD_RETRY * self._usual()[HEAD]:
            found, s = max(
                (found, s), self._search(frame, HEAD, starts[order[1]], self._zoom(head)), key=lambda match: match[1]
            )
        found[M] = np.clip(found[M], *self.head_lengths)
        self.p = adapt_threshold(self.p, moved.length, float(np.hypot(*(found[:2] - head[:2]))))
        return found, s

    def _track_torso(self, frame: np.ndarray, predicted: np.ndarray, head: np.ndarray) -> tuple[np.ndarray, float]:
        """Trunk searched from the prediction and at its usual length, the better kept: one colour lets it shrink."""
        usual = predicted.copy()
        usual[M] = self.lengths[TORSO] * self._zoom(head)
        return max(
            (self._search(frame, TORSO, start, self._zoom(head)) for start in (predicted, usual)),
            key=lambda match: match[1],
        )

    def _root(self, k: int, new: np.ndarray) -> np.ndarray:
        """Limb k's root (a shoulder or hip) carried by the trunk's motion to ``new``."""
        return from_block(to_block(self.blocks[k, :2], self.blocks[TORSO]), new[TORSO])

    def _limb_costs(self, new: np.ndarray, edges: Edges) -> dict:
        """Each limb's (upper, lower) block penalties: missing edges; for the lower block joint limits in 3D too."""
        key = self.trunk.follow(np.array([*(self._root(k, new) for k in ARMS), from_block(self.chest, new[TORSO])]))
        arm, leg = outline_cost(edges), outline_cost(edges, LEG_OUTLINE_COST)
        costs = {k: (arm, added(arm, arm_limits_cost(self.trunk.camera, key, n))) for n, k in enumerate(ARMS)}
        return costs | {
            k: (leg, added(leg, leg_limits_cost(self.trunk.camera, key, self._root(k, new), n, self.trunk.leg_lengths)))
            for n, k in enumerate(LEGS)
        }

    def _track_limb(self, image: np.ndarray, new: np.ndarray, s: np.ndarray, k: int, avoid: tuple) -> None:
        """Limb k from its root: best directions ``around_root``, then ``_hang``, kept off ``avoid``."""
        root = self._root(k, new)
        parts = [
            (self._model(i), self.grids[i], new[i, N], self.lengths[i] * new[HEAD, N] / self.head_width)
            for i in (k, k + 1)
        ]
        penalty = limb_penalty(root, new[k, N], self.blocks[k + 1], parts[1][3], avoid)
        upper_cost, lower_cost = self.limb_costs[k]
        penalty = added(penalty, lower_cost)
        lower = around_root(image, root, *parts, penalty, upper_cost, *self._upper_trust(k))
        self._hang(image, new, s, k, root, lower, penalty)

    def _hung_from(self, frame: np.ndarray, new: np.ndarray, s: np.ndarray, k: int, lower: np.ndarray):
        """(blocks, S): copies of ``new``, ``s`` with limb k hung from its root to a lower part searched from
        ``lower`` (5,) and kept near it."""
        root = self._root(k, new)
        length = self.lengths[k + 1] * new[HEAD, N] / self.head_width
        penalty = added(limb_penalty(root, new[k, N], lower, length, self._avoided(k, new)), self.limb_costs[k][1])
        placed, similarity = new.copy(), s.copy()
        self._hang(frame, placed, similarity, k, root, lower, penalty)
        return placed, similarity

    def _upper_trust(self, k: int) -> tuple[float, tuple[float, ...]]:
        """Limb k's upper-block 1/S weight and lengths tried around its root: less and shorter for the far arm."""
        if k + 1 == self.far_forearm:
            return FAR_UPPER_WEIGHT, FAR_UPPER_SCALES
        return 1.0, (1.0,)

    def _avoided(self, k: int, new: np.ndarray) -> tuple:
        """The (cost, block) pairs limb k's lower part keeps off: the head for an arm (skin matches the face)."""
        return ((HEAD_COST, new[HEAD].copy()),) if k in ARMS else ()

    def _part_twins(self, image: np.ndarray, new: np.ndarray, s: np.ndarray, twins: tuple[int, int]) -> None:
        """Twin limbs whose lower blocks overlap, tracked again each off the other's; least 1/S + overlap kept."""
        a, b = twins
        if twin_overlap(new[a + 1], new[b + 1]) < TWIN_OVERLAP:
            return
        options = [(new.copy(), s.copy())]
        for moved, kept in ((a, b), (b, a)):
            placed, similarity = new.copy(), s.copy()
            avoid = (*self._avoided(moved, new), (TWIN_COST, new[kept + 1].copy()))
            self._track_limb(image, placed, similarity, moved, avoid)
            options.append((placed, similarity))
        costs = [
            limb_cost(sim, a) + limb_cost(sim, b) + TWIN_COST * twin_overlap(n[a + 1], n[b + 1]) for n, sim in options
        ]
        new[:], s[:] = options[int(np.argmin(costs))]

    def _hang(
        self,
        image: np.ndarray,
        new: np.ndarray,
        s: np.ndarray,
        k: int,
        root: np.ndarray,
        lower: np.ndarray,
        penalty: blocks.Penalty,
    ) -> None:
        """Limb k's lower part searched from ``lower``, a leg's knee settled, the upper part from ``root`` to it."""
        new[k + 1], s[k + 1] = self._search(image, k + 1, lower, self._zoom(new[HEAD]), penalty)
        if k not in ARMS:
            new[k + 1], s[k + 1] = settled_knee(
                image,
                root,
                new[k + 1],
                (self._model(k), self.grids[k], new[k, N]),
                (self._model(k + 1), self.grids[k + 1]),
                self.limb_costs[k][0],
                penalty,
            )
        new[k] = blocks.between(root[None], new[k + 1, None, :2], new[k, N])[0]
        s[k] = blocks.score(image, self._model(k), self.grids[k], new[k])[0]

    def _model(self, k: int) -> np.ndarray:
        """Part k's colour model; the far forearm's own and its twin's mirrored as alternatives."""
        if k != self.far_forearm:
            return self.models[k]
        twin = self.models[TWIN_PART[k]]
        return np.stack([self.models[k], mirrored_model(twin, self.models[k].shape)])

    def _usual(self) -> np.ndarray:
        """(10,) every part's median S over the last HISTORY frames (inf before any)."""
        return np.median(self.history, axis=0) if self.history else np.full(len(PARTS), np.inf)

    def _update(self, frame: np.ndarray, new: np.ndarray, s: np.ndarray, lost: bool) -> None:
        """Velocities; colour models linearly weighted where S >= UPDATE_MIN of usual, unless lost or held."""
        self.velocity = new - self.blocks
        self.velocity[:, THETA] = (self.velocity[:, THETA] + np.pi) % (2 * np.pi) - np.pi
        self.blocks = new
        self.frame = frame
        if lost:
            return
        self.good = new.copy()
        if self.held:
            return
        self.history.append(s)
        for k in np.flatnonzero(s >= UPDATE_MIN * self._usual()):
            seen = blocks.sample_blocks(frame, new[k], self.grids[k])[0]
            adapted = (1 - UPDATE_RATE) * self.models[k] + UPDATE_RATE * seen
            self.models[k] = ANCHOR * self.marked[k] + (1 - ANCHOR) * adapted
