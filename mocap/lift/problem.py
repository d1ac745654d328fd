"""The clip solve's least-squares problem over a stretch of frames: residuals and their sparse
Jacobian.

Unknowns: every joint's x, y, z on the free frames (model units about the frame's observed 2D
pelvis; the pelvis's z stays 0, which orthography cannot see) and, with ``free_lengths``, one length
per bone class after them. Residuals, each over the error it allows (``Weights``): the 2D
reprojection under scaled orthography, or through the clip's pinhole camera where it has one and
the person model's depths (``Perspective``), weighted by each joint's confidence (a placed joint at
``sigma_placed``); joint accelerations about the pelvis; the pelvis between the hips and the neck
between the shoulders in depth; the person model's |dZ| with the frame's sign; the hips' and
shoulders' depths from the yaw; the clip's lengths about their estimate (all linear); bone lengths;
held and guessed signs (one-sided); knees and elbows bending one way (hinges)."""

from __future__ import annotations

import numpy as np
from scipy import sparse

from mocap.body import BODY_HEIGHT, JOINT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES
from mocap.lift.clipdata import (
    BONE_CLASS,
    BONE_FROM,
    BONE_TO,
    CLASSES,
    HINGES,
    N_JOINTS,
    PELVIS,
    SEGMENT_CLASS,
    TRUNK_BONE,
    ClipArrays,
    Weights,
    depth_scale,
)
from mocap.lift.taylor import UNIT_M, lateral_axis

_J = JOINT_INDEX
MIN_CONFIDENCE = 0.05  # a joint's confidence counts at least this much
NEAREST = 0.9  # of the pelvis's depth: how far toward the camera a joint may come


class Problem:
    """Frames ``frames`` of ``clip``: the free ones ``free`` ((n,) bool) start anywhere, the others
    stay at ``base`` ((n, 16, 3) model units); ``bones`` the class lengths, solved too with
    ``free_lengths``. ``residuals(x)`` and ``x0(start)`` speak of the flat unknowns."""

    def __init__(
        self,
        clip: ClipArrays,
        frames: slice,
        base: np.ndarray,
        free: np.ndarray,
        bones: np.ndarray,
        free_lengths: bool,
        weights: Weights,
    ):
        self.w = w = weights
        f = np.arange(frames.start, frames.stop)
        self.n = n = len(f)
        self.base = base.copy()
        self.mask = np.repeat(free[:, None, None], N_JOINTS, 1).repeat(3, 2)
        self.mask[:, PELVIS, 2] = False
        self.cols = np.full((n, N_JOINTS, 3), -1)
        self.cols[self.mask] = np.arange(self.mask.sum())
        self.n_p = int(self.mask.sum())
        self.bones0 = np.asarray(bones, float).copy()
        self.free_lengths = free_lengths
        self.n_x = self.n_p + (len(CLASSES) if free_lengths else 0)
        self._rows, self._cols, self._vals, self._flat, self._b, self._robust = [], [], [], [], [], []
        self._row = 0
        self.view: Perspective | None = None  # the pinhole's rows, where _image_rows takes them
        self._image_rows(clip, f)
        self._motion_rows(clip.fps)
        target = self._depth_rows(clip, f)
        self._yaw_rows(clip.yaw[f])
        self._finish_linear()
        self.sig_bone = np.where(TRUNK_BONE, w.sigma_trunk, w.sigma_bone) * BODY_HEIGHT
        self._sign_terms(clip, f, target)
        self.hinges = []
        for a, m, d, left, right, bend in HINGES:
            upper, lower = ("upper_leg", "lower_leg") if bend > 0 else ("upper_arm", "lower_arm")
            width = 2 * self.bones0[CLASSES.index("hip")] if bend > 0 else self.bones0[CLASSES.index("shoulders")]
            norm = self.bones0[CLASSES.index(upper)] * self.bones0[CLASSES.index(lower)] * width
            sigma = w.hinge_knee if bend > 0 else w.hinge_elbow
            self.hinges.append((_J[a], _J[m], _J[d], _J[left], _J[right], bend, 1.0 / sigma, norm))

    def _image_rows(self, clip: ClipArrays, f: np.ndarray) -> None:
        """The 2D reprojection (scaled orthography about the observed pelvis, or ``Perspective``'s rows where the
        clip has a camera and the person model's depths), by confidence."""
        w, n = self.w, self.n
        j2 = clip.joints2d[f]
        rel = (j2 - j2[:, [PELVIS]]) / clip.px_per_unit[f, None, None]
        seen = np.stack([rel[..., 0], -rel[..., 1]], axis=-1)  # (n, 16, 2) x right, y up
        conf = np.ones((n, N_JOINTS)) if clip.confidence is None else np.nan_to_num(clip.confidence[f])
        weight = np.sqrt(np.clip(conf, MIN_CONFIDENCE, 1.0)) / (w.sigma_2d * BODY_HEIGHT)
        if clip.placed is not None:
            weight = np.where(clip.placed[f], 1.0 / (w.sigma_placed * BODY_HEIGHT), weight)
        if clip.camera is not None and clip.depths is not None:
            self.view = Perspective.of(clip, f, seen, weight)
            return
        for c in range(2):
            self._linear([(np.arange(n)[:, None], np.arange(N_JOINTS)[None], c, weight)], weight * seen[..., c], True)

    def _motion_rows(self, fps: float) -> None:
        """Each joint's acceleration about the pelvis; the pelvis midway between the hips, the neck
        between the shoulders in depth."""
        w, n = self.w, self.n
        if n >= 3:
            sa = w.accel / (UNIT_M * fps**2)  # model units per frame^2
            mid = np.arange(1, n - 1)[:, None]
            others = np.array([j for j in range(N_JOINTS) if j != PELVIS])[None]
            pelvis = np.full_like(others, PELVIS)
            for c in range(3):
                steps = ((-1, 1.0), (0, -2.0), (1, 1.0))
                terms = [(mid + o, j, c, s * k / sa) for o, k in steps for j, s in ((others, 1.0), (pelvis, -1.0))]
                self._linear(terms, np.zeros((n - 2, others.shape[1])), robust=True)
        every = np.arange(n)[:, None]
        sb, st = w.sigma_bone * BODY_HEIGHT, w.sigma_trunk * BODY_HEIGHT
        for c in range(3):
            mids = [("hip_l", 0.5 / sb), ("hip_r", 0.5 / sb), ("pelvis", -1.0 / sb)]
            self._linear([(every, np.array([[_J[j]]]), c, v) for j, v in mids], np.zeros((n, 1)))
        mids = [("shoulder_l", 0.5 / st), ("shoulder_r", 0.5 / st), ("neck", -1.0 / st)]
        self._linear([(every, np.array([[_J[j]]]), 2, v) for j, v in mids], np.zeros((n, 1)))

    def _depth_rows(self, clip: ClipArrays, f: np.ndarray) -> np.ndarray:
        """The person model's |dZ| signed by the held or guessed sign; (n, 10) those targets (NaN: none)."""
        target = np.full((self.n, len(SEGMENT_NAMES)), np.nan)
        if clip.depths is not None:
            target = clip.held_or_guessed()[f] * clip.depths[f] * depth_scale(clip, self.bones0)
            rows_f, segs = np.nonzero(np.isfinite(target))
            v = np.full(len(segs), 1 / (self.w.sigma_depth * BODY_HEIGHT))
            terms = [(rows_f, SEGMENT_JOINTS[segs, 1], 2, v), (rows_f, SEGMENT_JOINTS[segs, 0], 2, -v)]
            self._linear(terms, target[rows_f, segs] * v, robust=True)
        return target

    def _yaw_rows(self, yaw: np.ndarray) -> None:
        """The hips' and shoulders' depths from the yaw: the performer's left (hip_r -> hip_l,
        shoulder_r -> shoulder_l) along lateral_axis."""
        across = np.array([lateral_axis(y)[2] if np.isfinite(y) else np.nan for y in yaw])
        rows_f = np.flatnonzero(np.isfinite(across))
        for left, right, width in (
            ("hip_l", "hip_r", 2 * self.bones0[CLASSES.index("hip")]),
            ("shoulder_l", "shoulder_r", self.bones0[CLASSES.index("shoulders")]),
        ):
            v = np.full(len(rows_f), 1 / (self.w.sigma_yaw * width))
            terms = [(rows_f, np.full(len(rows_f), _J[left]), 2, v), (rows_f, np.full(len(rows_f), _J[right]), 2, -v)]
            self._linear(terms, width * across[rows_f] * v)

    def _sign_terms(self, clip: ClipArrays, f: np.ndarray, target: np.ndarray) -> None:
        """The held signs, and the guessed ones where the person model gives no depth (one-sided)."""
        w = self.w
        held = clip.held_signs()[f]
        guess = np.where((held == 0) & ~np.isfinite(target), clip.signs[f], 0).astype(int)
        self.sign_terms = []
        for values, sigma in ((held, w.sigma_held), (guess, w.sigma_guess)):
            rows_f, segs = np.nonzero(values)
            if len(segs):
                margin = w.sign_margin * self.bones0[SEGMENT_CLASS[segs]]
                weight = 1 / (sigma * BODY_HEIGHT)
                self.sign_terms.append((rows_f, segs, values[rows_f, segs].astype(float), weight, margin))

    def _linear(self, terms, target, robust: bool = False) -> None:
        """Rows sum(coef * P[frame, joint, coord]) - target, one per element of ``target``; ``terms``
        (frames, joints, coord, coef) broadcast to ``target``'s shape."""
        target = np.asarray(target, float)
        rows = self._row + np.arange(target.size).reshape(target.shape)
        for frames, joints, c, coef in terms:
            fr, jo, co = (np.broadcast_to(a, target.shape) for a in np.broadcast_arrays(frames, joints, coef))
            self._rows.append(rows.ravel())
            self._cols.append(self.cols[fr, jo, c].ravel())
            self._vals.append(np.asarray(co, float).ravel())
            self._flat.append(((fr * N_JOINTS + jo) * 3 + c).ravel())
        self._b.append(target.ravel())
        self._robust.append(np.full(target.size, robust))
        self._row += target.size

    def _finish_linear(self) -> None:
        """The linear rows as A x - b, held coordinates moved into b; the lengths' prior last."""
        if self.free_lengths:
            sl = self.w.sigma_length * self.bones0
            self._rows.append(self._row + np.arange(len(CLASSES)))
            self._cols.append(self.n_p + np.arange(len(CLASSES)))
            self._vals.append(1 / sl)
            self._flat.append(np.zeros(len(CLASSES), int))
            self._b.append(self.bones0 / sl)
            self._robust.append(np.zeros(len(CLASSES), bool))
            self._row += len(CLASSES)
        rows, cols, vals, flat = (np.concatenate(a) for a in (self._rows, self._cols, self._vals, self._flat))
        free = cols >= 0
        self.n_lin = self._row
        self.robust = np.concatenate(self._robust)
        if self.view is not None:  # the reprojection, first of the nonlinear rows, is robust too
            self.robust = np.concatenate([self.robust, np.ones(self.view.seen.size, bool)])
        self.A = sparse.csr_matrix((vals[free], (rows[free], cols[free])), shape=(self.n_lin, self.n_x))
        held = self.base.reshape(-1)[flat[~free]]
        self.b = np.concatenate(self._b) - np.bincount(rows[~free], vals[~free] * held, minlength=self.n_lin)
        del self._rows, self._cols, self._vals, self._flat, self._b, self._robust

    def positions(self, x: np.ndarray) -> np.ndarray:
        """(n, 16, 3) the stretch's poses at unknowns ``x``."""
        p = self.base.copy()
        p[self.mask] = x[: self.n_p]
        return p

    def lengths(self, x: np.ndarray) -> np.ndarray:
        """(len(CLASSES),) the class lengths at unknowns ``x``."""
        return x[self.n_p :] if self.free_lengths else self.bones0

    def x0(self, start: np.ndarray) -> np.ndarray:
        """The unknowns of poses ``start`` (n, 16, 3) and the first lengths."""
        x = start[self.mask]
        return np.concatenate([x, self.bones0]) if self.free_lengths else x

    def residuals(self, x: np.ndarray, jac: bool = False):
        """Residuals (linear rows first, ``n_lin`` of them), and with ``jac`` their sparse Jacobian."""
        p, lengths = self.positions(x), self.lengths(x)
        out = [self.A @ x - self.b]
        rows, cols, vals = [], [], []
        row = self.n_lin

        def entries(rid, joints, grads):
            """Jacobian entries of rows ``rid`` on joints ``joints`` with (.., 3) gradients ``grads``."""
            frames = np.broadcast_to(np.arange(self.n).reshape((-1,) + (1,) * (np.ndim(rid) - 1)), np.shape(rid))
            for c in range(3):
                rows.append(np.ravel(rid))
                cols.append(self.cols[frames, joints, c].ravel())
                vals.append(np.ravel(grads[..., c]))

        if self.view is not None:
            r, grads = self.view.residuals(p)
            out.append(r.ravel())
            if jac:
                rid = row + np.arange(r.size).reshape(r.shape)
                entries(rid, np.broadcast_to(np.arange(N_JOINTS)[None, :, None], r.shape), grads)
            row += r.size
        # bone lengths
        d = p[:, BONE_TO] - p[:, BONE_FROM]  # (n, B, 3)
        norm = np.maximum(np.linalg.norm(d, axis=-1), 1e-9)
        r = (norm - lengths[BONE_CLASS]) / self.sig_bone
        out.append(r.ravel())
        if jac:
            rid = row + np.arange(r.size).reshape(r.shape)
            g = d / norm[..., None] / self.sig_bone[:, None]
            entries(rid, np.broadcast_to(BONE_TO, r.shape), g)
            entries(rid, np.broadcast_to(BONE_FROM, r.shape), -g)
            if self.free_lengths:
                rows.append(rid.ravel())
                cols.append(np.broadcast_to(self.n_p + BONE_CLASS, r.shape).ravel())
                vals.append(np.broadcast_to(-1.0 / self.sig_bone, r.shape).ravel())
        row += r.size
        # held and guessed signs: |dZ| of at least ``margin`` on the sign's side
        for fr, segs, value, weight, margin in self.sign_terms:
            a, b = SEGMENT_JOINTS[segs, 0], SEGMENT_JOINTS[segs, 1]
            gap = margin - value * (p[fr, b, 2] - p[fr, a, 2])
            out.append(np.where(gap > 0, weight * gap, 0.0))
            if jac:
                rid = row + np.arange(len(segs))
                coef = np.where(gap > 0, -weight * value, 0.0)
                rows.extend([rid, rid])
                cols.extend([self.cols[fr, b, 2], self.cols[fr, a, 2]])
                vals.extend([coef, -coef])
            row += len(segs)
        # hinges bend one way
        for a, m, dd, left, right, bend, weight, scale in self.hinges:
            t, u, axis = p[:, m] - p[:, a], p[:, dd] - p[:, m], p[:, left] - p[:, right]
            gap = -bend * np.einsum("fi,fi->f", np.cross(t, u), axis) / scale
            out.append(np.where(gap > 0, weight * gap, 0.0))
            if jac:
                rid = row + np.arange(self.n)
                k = np.where(gap > 0, -bend * weight / scale, 0.0)[:, None]
                on = k != 0  # only where the hinge breaks (elsewhere, and where a joint is unknown, 0)
                dt, du, dl = (np.where(on, np.cross(x, y) * k, 0.0) for x, y in ((u, axis), (axis, t), (t, u)))
                for joint, grad in ((m, dt - du), (a, -dt), (dd, du), (left, dl), (right, -dl)):
                    entries(rid, np.full(self.n, joint), grad)
            row += self.n
        res = np.concatenate(out)
        if not jac:
            return res
        rows, cols, vals = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
        keep = cols >= 0
        shape = (row - self.n_lin, self.n_x)
        nonlinear = sparse.csr_matrix((vals[keep], (rows[keep] - self.n_lin, cols[keep])), shape=shape)
        return res, sparse.vstack([self.A, nonlinear], format="csr")


class Perspective:
    """The 2D reprojection through a pinhole camera (``ClipArrays.camera``, with the person model's depths), in
    the problem's terms: each frame's pelvis at depth ``depth`` = focal / px_per_unit (model units) and
    ``offset`` (n, 2) model units, x right, y up, from the principal point's ray; a joint at (x, y, z) about the
    pelvis is seen at depth / (depth - z) times its offset, less the pelvis's: the orthographic row's
    perspective. ``seen`` (n, 16, 2) and ``weight`` (n, 16) as the orthographic rows'."""

    def __init__(self, depth: np.ndarray, offset: np.ndarray, seen: np.ndarray, weight: np.ndarray):
        self.depth, self.offset, self.seen, self.weight = depth, offset, seen, weight

    @classmethod
    def of(cls, clip: ClipArrays, f: np.ndarray, seen: np.ndarray, weight: np.ndarray) -> "Perspective":
        """The frames ``f`` of ``clip``, whose camera is known, seen and weighted as the orthographic rows."""
        cam, ppu = clip.camera, clip.px_per_unit[f]
        pelvis = clip.joints2d[f, PELVIS]
        offset = np.stack([(pelvis[:, 0] - cam.cx) / ppu, (cam.cy - pelvis[:, 1]) / ppu], axis=-1)
        return cls(cam.focal / ppu, offset, seen, weight)

    def residuals(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((n, 16, 2) weighted reprojection residuals of poses ``p`` (n, 16, 3), (n, 16, 2, 3) their gradients
        in each joint's x, y, z)."""
        depth = self.depth[:, None]
        near = np.minimum(p[..., 2], NEAREST * depth)  # no joint at or behind the camera
        k = depth / (depth - near)  # (n, 16)
        ray = self.offset[:, None, :] + p[..., :2]  # (n, 16, 2)
        w = self.weight[..., None]
        r = w * (k[..., None] * ray - self.offset[:, None, :] - self.seen)
        grads = np.zeros(r.shape + (3,))
        for c in range(2):
            grads[..., c, c] = w[..., 0] * k
            grads[..., c, 2] = np.where(p[..., 2] < NEAREST * depth, w[..., 0] * ray[..., c] * k * k / depth, 0.0)
        return r, grads
