"""Tracking the marked body from one frame to the next, head to feet: the tracking
paper's feature tracking (Pan, Zhuang and Liu, *Video motion capture in VBA*, 2000,
section "Feature tracking").

Each of the 10 body parts is a morph block (mocap.track.blocks) from one of its joints to the
other, as wide as its cylinder (body.WIDTH; the torso as wide as the marked shoulders
show it turned) at the marked skeleton's scale. Its colours on frame 0 are its colour
model; beyond the paper, an arm's sub-pixels weigh as much as they tell the arm from what
lies beside it there (mocap.track.parts.told_apart). Every later frame is tracked head to feet:

1. the head (calvaria to neck): its calvaria predicted by image difference
   (mocap.track.headmotion, Eq. 1-5 of the head part) or by constant velocity, whichever
   start the block match scores higher (a moving background breaks the image
   difference's premise of a still background), then the morph-block search of
   position, angle and scale along the search path (Fig. 6), from the other start
   too where that match is poor (``_track_head``);
2. the trunk hanging from the neck (angle and length); the chest keeps its marked
   place in the trunk's frame; shoulders and hips move with the trunk;
3. each limb from its root, carried by the trunk: beyond the paper, found afresh on
   every frame as the best pair of directions of its parts all around the root
   (``around_root``), then its lower part's position, angle and length searched
   from there, with the upper part from the root to the lower part's start. The
   paper starts every part where constant velocity predicts it; a limb, which
   swings back and forth, is badly predicted that way and once lost (to clutter,
   to its twin) is not found again. The lower part is kept off the places where
   it cannot be (``limb_penalty``: its own upper part, the head for an arm, its twin
   limb's lower part, ``_part_twins``) and near where it was on the last frame;
   a limb's blocks pay for sides the frame shows no edge along (``outline_cost``),
   and its lower block for a pose a human limb cannot take in 3D (``arm_limits_cost``,
   ``leg_limits_cost``, measured from the key triangle followed in 3D as the
   reconstruction does, ``TrunkDepth``);
   a leg's knee is then settled where its thigh and shin blocks match best together
   (``settled_knee``). The far arm's forearm matches either its own colours or its
   twin's mirrored (``far_forearm``): marked behind the trunk, its own are the shirt's;
   its upper arm's match weighs less around the root (``_upper_trust``);
4. every colour model updated by linear weighting with its new block when the match
   is as good as the part's usual one; beyond the paper, the update keeps ANCHOR of
   the marked frame's colours, so that a model cannot drift onto clutter.

The similarity S of each part's match is its reliability on that frame.

The parts, their blocks' search and their colour models are mocap.track.parts; a
limb's search around its root and the penalties of its blocks mocap.track.limbs; here
the frame loop that carries them from frame to frame.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from mocap.body import JOINT_INDEX
from mocap.edges import Edges
from mocap.track import blocks
from mocap.track.blocks import M, N, THETA, X, Y, block_end, from_block, to_block
from mocap.track.calibration import Pinhole, default_camera
from mocap.track.headmotion import P_START, adapt_threshold, head_displacement
from mocap.track.loss import DISTINCT, body_lost, part_confidence
from mocap.track.limbs import (HEAD_COST, LEG_OUTLINE_COST, TWIN_COST, TWIN_OVERLAP, TrunkDepth, added,
                               arm_limits_cost, around_root, leg_limits_cost, limb_cost, limb_penalty,
                               outline_cost, settled_knee, twin_overlap)
from mocap.track.marks import body_scale
from mocap.track.reacquire import carried, distinctness, reacquired, scan_heads
from mocap.track.parts import (ARMS, HEAD, LEGS, LIMBS, PART_JOINTS, PARTS, TORSO, TWIN_PART, TWINS,
                               arm_grids, far_forearm, mirrored_model, part_lengths, part_widths, search_part, skeleton)

BEYOND = 0.3               # of a part's length: the block reaches this far past both joints
MAX_STRETCH = 1.15         # a part is seen at most this much longer than its length
UPDATE_RATE = 0.3          # linear weighting of a colour model by the new block
UPDATE_MIN = 0.9           # of the part's median S so far: worse matches leave the model
ANCHOR = 0.5               # weight of frame 0's colours in every updated model
HISTORY = 150              # frames of S that the median looks back on
USUAL_MIN = 0.6            # of a part's model length: the least usual length (around_root)
ZOOM_RANGE = (0.5, 2.0)    # of the marked head's length: the head's (the body's) scale stays in it
HEAD_RETRY = 0.3           # of the head's median S: a worse match is searched again (_track_head)
FAR_UPPER_WEIGHT = 0.3     # of its 1/S: what the far arm's upper arm's match weighs around its root
FAR_UPPER_SCALES = (1.0, 0.9)   # of its usual length: the far arm's upper arm's lengths tried there


class BodyTracker:
    """The state carried from frame to frame: every part's block and its change over
    the last frame (constant-velocity prediction), the colour models and the
    similarities of the last HISTORY frames, the head's adaptive threshold p, the
    last frame and the trunk in 3D (``TrunkDepth``, seen by ``camera``, default the
    frame's (mocap.track.calibration.default_camera), and turned to ``turn``), and
    every part's confidence on the last frame (mocap.track.loss, at ``fps``)."""

    def __init__(self, frame0: np.ndarray, marks: np.ndarray, camera: Pinhole | None = None,
                 turn: str | None = None, fps: float = 25.0):
        scale = body_scale(marks)
        self.fps = fps
        self.trunk = TrunkDepth(marks, camera or default_camera(frame0.shape[1], frame0.shape[0]), turn)
        self.limb_costs: dict[int, tuple[blocks.Penalty, blocks.Penalty]] = {}
        self.blocks = blocks.between(marks[PART_JOINTS[:, 0]], marks[PART_JOINTS[:, 1]],
                                     part_widths(marks, scale))
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
        self.grids = arm_grids(frame0, self.blocks, [blocks.make_grid(b[M], b[N], 0.0 if k == HEAD else BEYOND)
                                                     for k, b in enumerate(self.blocks)], self.far_forearm)
        self.models = [blocks.sample_blocks(frame0, b, g)[0]
                       for b, g in zip(self.blocks, self.grids)]
        self.marked = list(self.models)
        self.good = self.blocks.copy()
        self.history: deque[np.ndarray] = deque(maxlen=HISTORY)
        self.chest = to_block(marks[JOINT_INDEX["chest"]], self.blocks[TORSO])
        self.p = P_START
        self.frame = frame0

    def step(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Track the next frame: its (16, 2) joints and the (10,) similarities S."""
        predicted = self._predicted()
        new, s = predicted.copy(), np.zeros(len(PARTS))
        new[HEAD], s[HEAD] = self._track_head(frame, predicted[HEAD])
        predicted[TORSO, :2] = block_end(new[HEAD])
        new[TORSO], s[TORSO] = self._track_torso(frame, predicted[TORSO], new[HEAD])
        refound = self.lost and self._reacquire(frame, new, s)
        self.limb_costs = self._limb_costs(new, Edges.of_frame(frame))
        for k in LIMBS:
            self._track_limb(frame, new, s, k, self._avoided(k, new))
        for twins in TWINS:
            self._part_twins(frame, new, s, twins)
        new = self._bounded(new, frame.shape)
        self.confidence = self._confidence(new, s, frame.shape)
        self.lost = self._judged_lost(frame, new, s, refound)
        self._update(frame, new, s, self.lost)
        return skeleton(new, self.chest), s

    def _judged_lost(self, frame: np.ndarray, new: np.ndarray, s: np.ndarray, refound: bool) -> bool:
        """Whether the body is lost on a frame tracked to ``new`` with similarities
        ``s`` (``refound``: re-acquisition found it there): not where its head and
        trunk stand out of the frame (``_held``); else, once lost, until
        re-acquisition finds it (the tracker's own match drifts on clutter that now
        and then matches as well as the body).

        Beyond the paper: a match judged against the part's usual S alone is lost
        for good where what lies behind the body changes (a pale board passes behind
        the head: its S halves and stays there, and the usual S of the frames before
        never comes back); a frame where the head and the trunk still stand out is
        judged by the other checks of mocap.track.loss alone (``self.held``: it
        teaches neither the usual S nor the colour models, which would follow a
        tracker gone off the body). benchmarks/bench_track.py's cmu_01_01_jumps
        (yaw 45) was lost from frame 10 to its end (289 of 299 frames, PA-MPJPE 120.5
        mm), now on 48 (68.2 mm). Where the usual S restarted from a held frame's,
        bench_track_clips.py's laugh_arms_up and salsa_spin answered frames whose
        trunk was 10-37% of the body's height off."""
        lost = self.lost and not refound or bool(body_lost(self.confidence, self.lost))
        self.held = lost and self._held(frame, new)
        if not self.held:
            return lost
        self.confidence = self._confidence(new, s, frame.shape, np.full(len(PARTS), np.inf))
        return bool(body_lost(self.confidence))

    def _held(self, frame: np.ndarray, new: np.ndarray) -> bool:
        """Whether the head and the trunk of ``new`` both match at least DISTINCT
        times better where they lie than anywhere else in the frame
        (mocap.track.reacquire.distinctness)."""
        return all(distinctness(frame, self._model(k), self.grids[k], new[k]) >= DISTINCT
                   for k in (HEAD, TORSO))

    def _reacquire(self, frame: np.ndarray, new: np.ndarray, s: np.ndarray) -> bool:
        """Whether the head and trunk of a frame where the body was lost are found
        again (mocap.track.reacquire), from the head tracked on it (``new``, the
        image difference's), the last good pose's and the best places of the head's
        colours over the whole frame. If so, they go into ``new`` and ``s``, and the
        limbs start from the last good pose carried by the trunk found."""
        starts = np.concatenate([new[[HEAD]], self.good[[HEAD]],
                                 scan_heads(frame, self._model(HEAD), self.grids[HEAD], self.good[HEAD])])
        found = reacquired(frame, starts, self.good, self._usual(), self._head_search,
                           self._track_torso, self._score)
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

    def _confidence(self, new: np.ndarray, s: np.ndarray, shape: tuple,
                    usual: np.ndarray | None = None) -> np.ndarray:
        """(10,) the parts' confidence on a frame (mocap.track.loss.part_confidence)
        against their ``usual`` S (default ``_usual``); a part's calibrated length
        follows the head's zoom."""
        expected = self.longest / MAX_STRETCH * new[HEAD, N] / self.head_width
        usual = self._usual() if usual is None else usual
        return part_confidence(new, self.blocks, s, usual, expected, shape, self.fps)

    def _bounded(self, new: np.ndarray, shape: tuple) -> np.ndarray:
        """The blocks kept sane where the match ran off (a body too small or lost):
        starts inside the frame, widths and lengths within ZOOM_RANGE of the marked
        ones, the last frame's block where a value is not finite."""
        new = np.where(np.isfinite(new), new, self.blocks)
        new[:, X] = np.clip(new[:, X], 0, shape[1] - 1)
        new[:, Y] = np.clip(new[:, Y], 0, shape[0] - 1)
        new[:, N] = np.clip(new[:, N], self.widths[:, 0], self.widths[:, 1])
        new[:, M] = np.clip(new[:, M], 2.0, ZOOM_RANGE[1] * self.longest)
        return new

    def _predicted(self) -> np.ndarray:
        """Every block changed as over the last frame; widths follow the head's zoom
        (the whole body nears or recedes), which stays within ZOOM_RANGE of the marks."""
        predicted = self.blocks + self.velocity
        predicted[:, M] = np.maximum(predicted[:, M], 2.0)
        predicted[HEAD, M] = np.clip(predicted[HEAD, M], *self.head_lengths)
        predicted[1:, N] = self.blocks[1:, N] * predicted[HEAD, M] / self.blocks[HEAD, M]
        return predicted

    def _search(self, image: np.ndarray, k: int, start: np.ndarray, zoom: float,
                penalty: blocks.Penalty | None = None):
        """Part k's block and S searched from ``start`` (search_part), the body at
        ``zoom`` (``_zoom``)."""
        return search_part(image, self._model(k), self.grids[k], start, PARTS[k],
                           self.longest[k] * zoom, penalty)

    def _zoom(self, head: np.ndarray) -> float:
        """The body's scale on a frame against the marks' by its ``head`` block."""
        return float(head[N] / self.head_width)

    def _track_head(self, frame: np.ndarray, predicted: np.ndarray) -> tuple[np.ndarray, float]:
        """The head block, searched from the better of the image difference's and
        constant velocity's calvaria, and where its match is worse than HEAD_RETRY of
        the head's usual S, from the other one too, the better match kept; then p
        adapts to the displacement found.

        Beyond the paper: over a moving background the image difference's start can
        lie far off, on a place that matches the head as badly as the right start
        does, and the search around it ends on clutter (a repeated frame, which stops
        constant velocity, then a step of 5 px: the head 26 px off, S 0.03 against
        0.14 at its place). With the head the whole body is lost: bench_track's
        motions seen 10 degrees from profile (render yaws 10 and 170) lost it on 123
        frames of both walk01 clips; searched again, on none (PA-MPJPE 97.4 -> 76.9
        mm; bench_track's own views 64.8 -> 64.7, its held-out ones 76.2 -> 77.2, where
        walk01 120's legs are lost on another path)."""
        head = self.blocks[HEAD]
        moved = head_displacement(self.frame, frame, head[:2], block_end(head), self.p)
        starts = np.stack([np.r_[head[:2] + moved.vector, predicted[2:]], predicted])
        order = np.argsort(-blocks.score(frame, self.models[HEAD], self.grids[HEAD], starts))
        found, s = self._search(frame, HEAD, starts[order[0]], self._zoom(head))
        if s < HEAD_RETRY * self._usual()[HEAD]:
            found, s = max((found, s), self._search(frame, HEAD, starts[order[1]], self._zoom(head)),
                           key=lambda match: match[1])
        found[M] = np.clip(found[M], *self.head_lengths)
        self.p = adapt_threshold(self.p, moved.length, float(np.hypot(*(found[:2] - head[:2]))))
        return found, s

    def _track_torso(self, frame: np.ndarray, predicted: np.ndarray,
                     head: np.ndarray) -> tuple[np.ndarray, float]:
        """The trunk's block searched from the predicted one and from it at the
        trunk's usual length at the zoom of ``head``, the better match kept.

        Beyond the paper: a trunk of one colour matches about as well at many lengths
        (the bottom of the block slides up the shirt), and an arm swinging across it
        makes a shorter block match as well for a few frames; a search that changes
        the length by a tenth a frame then shrinks the trunk to half its length and
        stays in that local optimum when the arm has passed (track_walk: the pelvis
        35 px up a 86 px trunk, the legs hanging from there)."""
        usual = predicted.copy()
        usual[M] = self.lengths[TORSO] * self._zoom(head)
        return max((self._search(frame, TORSO, start, self._zoom(head)) for start in (predicted, usual)),
                   key=lambda match: match[1])

    def _root(self, k: int, new: np.ndarray) -> np.ndarray:
        """Limb k's root (a shoulder or hip) carried by the trunk's motion to ``new``."""
        return from_block(to_block(self.blocks[k, :2], self.blocks[TORSO]), new[TORSO])

    def _limb_costs(self, new: np.ndarray, edges: Edges) -> dict:
        """Each limb's (upper, lower) block penalties on a frame whose trunk is placed:
        the frame's ``edges`` along both (outline_cost: OUTLINE_COST for an arm,
        LEG_OUTLINE_COST for a leg), the lower block also the joint limits
        (``arm_limits_cost``, ``leg_limits_cost``) in the key triangle's 3D (``TrunkDepth``)."""
        key = self.trunk.follow(np.array([*(self._root(k, new) for k in ARMS),
                                          from_block(self.chest, new[TORSO])]))
        arm, leg = outline_cost(edges), outline_cost(edges, LEG_OUTLINE_COST)
        costs = {k: (arm, added(arm, arm_limits_cost(self.trunk.camera, key, n)))
                 for n, k in enumerate(ARMS)}
        return costs | {k: (leg, added(leg, leg_limits_cost(self.trunk.camera, key, self._root(k, new), n,
                                                            self.trunk.leg_lengths)))
                        for n, k in enumerate(LEGS)}

    def _track_limb(self, image: np.ndarray, new: np.ndarray, s: np.ndarray, k: int,
                    avoid: tuple) -> None:
        """A limb (parts k, k + 1) from its root carried by the trunk's motion: the
        best pair of directions all around the root (``around_root``), then the
        lower part searched from there (``_hang``), kept off its upper part and the
        blocks to ``avoid`` and near its last place (limb_penalty); its blocks also
        charged the frame's ``limb_costs``."""
        root = self._root(k, new)
        parts = [(self._model(i), self.grids[i], new[i, N],
                  self.lengths[i] * new[HEAD, N] / self.head_width) for i in (k, k + 1)]
        penalty = limb_penalty(root, new[k, N], self.blocks[k + 1], parts[1][3], avoid)
        upper_cost, lower_cost = self.limb_costs[k]
        penalty = added(penalty, lower_cost)
        lower = around_root(image, root, *parts, penalty, upper_cost, *self._upper_trust(k))
        self._hang(image, new, s, k, root, lower, penalty)

    def _upper_trust(self, k: int) -> tuple[float, tuple[float, ...]]:
        """Beyond the paper: the weight of limb k's upper block's 1/S around its root
        (``around_root``) and the lengths tried there, of its usual one. The far
        arm's upper arm (of ``far_forearm``), marked on or behind the trunk in the
        shaded shirt's colours, matches the trunk better than its own place
        (track_salsa's raised left sleeve, lit 1.6 times brighter: 28-36 grey levels
        there, 7-9 on the trunk): it weighs FAR_UPPER_WEIGHT, so that its forearm's
        skin decides, and, often turned toward or away from the camera, is also tried
        shorter (FAR_UPPER_SCALES), or the forearm hung from its end misses. A far arm
        hidden behind the trunk then strays more (the README gives the measures)."""
        if k + 1 == self.far_forearm:
            return FAR_UPPER_WEIGHT, FAR_UPPER_SCALES
        return 1.0, (1.0,)

    def _avoided(self, k: int, new: np.ndarray) -> tuple:
        """The (cost, block) pairs limb k's lower part keeps off: the head for an arm
        (a forearm's skin matches the face and neck)."""
        return ((HEAD_COST, new[HEAD].copy()),) if k in ARMS else ()

    def _part_twins(self, image: np.ndarray, new: np.ndarray, s: np.ndarray,
                    twins: tuple[int, int]) -> None:
        """Beyond the paper: twin limbs (both arms, both legs) look alike, and a limb
        that lost its own place follows its twin's. Where their lower blocks lie on
        one another (TWIN_OVERLAP), each twin in turn is tracked again keeping off
        the other's lower block (TWIN_COST); the placement of least joint cost (both
        limbs' 1/S and TWIN_COST times their overlap) stays."""
        a, b = twins
        if twin_overlap(new[a + 1], new[b + 1]) < TWIN_OVERLAP:
            return
        options = [(new.copy(), s.copy())]
        for moved, kept in ((a, b), (b, a)):
            placed, similarity = new.copy(), s.copy()
            avoid = (*self._avoided(moved, new), (TWIN_COST, new[kept + 1].copy()))
            self._track_limb(image, placed, similarity, moved, avoid)
            options.append((placed, similarity))
        costs = [limb_cost(sim, a) + limb_cost(sim, b)
                 + TWIN_COST * twin_overlap(n[a + 1], n[b + 1]) for n, sim in options]
        new[:], s[:] = options[int(np.argmin(costs))]

    def _hang(self, image: np.ndarray, new: np.ndarray, s: np.ndarray, k: int,
              root: np.ndarray, lower: np.ndarray, penalty: blocks.Penalty) -> None:
        """Limb k from its ``root`` and the lower part searched from ``lower`` (its
        candidates charged ``penalty``), a leg's knee settled (``settled_knee``): the
        upper part then runs from the root to where the lower part begins."""
        new[k + 1], s[k + 1] = self._search(image, k + 1, lower, self._zoom(new[HEAD]), penalty)
        if k not in ARMS:
            new[k + 1], s[k + 1] = settled_knee(
                image, root, new[k + 1], (self._model(k), self.grids[k], new[k, N]),
                (self._model(k + 1), self.grids[k + 1]), self.limb_costs[k][0], penalty)
        new[k] = blocks.between(root[None], new[k + 1, None, :2], new[k, N])[0]
        s[k] = blocks.score(image, self._model(k), self.grids[k], new[k])[0]

    def _model(self, k: int) -> np.ndarray:
        """The colour model part k is matched against: its own, or for the far arm's
        forearm (``far_forearm``) its own and its twin's mirrored as alternatives
        (blocks.similarity)."""
        if k != self.far_forearm:
            return self.models[k]
        twin = self.models[TWIN_PART[k]]
        return np.stack([self.models[k], mirrored_model(twin, self.models[k].shape)])

    def _usual(self) -> np.ndarray:
        """(10,) every part's median S over the last HISTORY frames (inf before any)."""
        return np.median(self.history, axis=0) if self.history else np.full(len(PARTS), np.inf)

    def _update(self, frame: np.ndarray, new: np.ndarray, s: np.ndarray, lost: bool) -> None:
        """Velocities; colour models by linear weighting (matches at least UPDATE_MIN
        of the part's median S only, so an occluder's colours stay out). A frame where
        the body is ``lost`` changes neither the usual S nor the models (a lost
        tracker's matches would teach them the clutter it follows), nor one where it
        is held by standing out alone (``_judged_lost``: its matches lie far below
        the usual S, and would lower it)."""
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
