"""A synthetic performer: projected 3D joints plus a :class:`~clone.synth.appearance.Look` -> an RGB frame.

The body is built from a handful of analytic primitives around the joints (:mod:`clone.synth.raster`):

- limbs (upper/lower arm, thigh, shin), neck, hands, feet: tapered capsules;
- torso (and skirt): an elliptic cylinder between the shoulders and the hips whose cross-section turns
  with the shoulder and hip lines in 3D, so it is wide from the front and narrow from the side;
- head: a slightly tall ellipsoid with hair on top and at the back and skin, eyes and mouth at the
  front, decided from where the nose is, so the frame shows which way the person faces.

Clothes follow the body (:mod:`clone.synth.paint`): shirt on the torso and sleeves, trousers/shorts/skirt
on the legs, shoes, a belt, and stripes or checks that move with the body. A V-neck on the front of the
shirt tells front from back.

Coordinates: ``xy`` in pixels (x right, y down, pixel centres at integers), ``depth`` in metres, larger
is farther; ``px_per_m`` converts metres across the image to pixels (a weak-perspective camera).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from clone.synth.appearance import Look
from clone.synth.paint import Bands, Materials
from clone.synth.raster import NormalPaint, Rasterizer
from retarget.world.skeleton import WORLD_JOINTS

_EYE = np.array([34, 26, 24], dtype=np.float32)
_MOUTH = np.array([150, 72, 70], dtype=np.float32)
_UP = np.array([0.0, -1.0, 0.0])  # image up in camera coordinates (y down)

Part = tuple[float, Callable[[], None]]  # (mean depth in metres, draw it)


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-9 else fallback


def _section(half_a: float, lateral: np.ndarray, half_b: float, forward: np.ndarray, perp: np.ndarray) -> np.ndarray:
    """[2, 2] cross-section matrix: columns = half axes (lateral, forward) in (image-lateral, depth) metres."""
    e1 = np.array([np.dot(lateral[:2], perp), lateral[2]])
    e2 = np.array([np.dot(forward[:2], perp), forward[2]])
    return np.stack([half_a * e1, half_b * e2], axis=1)


def _face_paint(face: np.ndarray, up: np.ndarray, side: np.ndarray, hair_style: str, skin: np.ndarray,
                hair: np.ndarray) -> NormalPaint:
    """Head colours from the surface normal: hair above a hairline, two eyes and a mouth on the face side.

    Args:
        face, up, side: [3] unit vectors the face looks along, the head's up, and the head's side.
        hair_style: one of ``HAIR_STYLES``.
        skin, hair: [3] float32 RGB.
    """
    eyes = [_unit(face * 0.86 + up * 0.16 + side * s, face).astype(np.float32) for s in (0.42, -0.42)]
    f32, u32, s32 = face.astype(np.float32), up.astype(np.float32), side.astype(np.float32)

    def paint(nx: np.ndarray, ny: np.ndarray, nz: np.ndarray) -> np.ndarray:
        df = nx * f32[0] + ny * f32[1] + nz * f32[2]
        du = nx * u32[0] + ny * u32[1] + nz * u32[2]
        # The hairline: how high up the head (du) hair starts, as a curve over front-back (df): at
        # the forehead, above the ears, down to the nape.
        if hair_style == "bald":
            is_hair = du > 0.75
        elif hair_style == "long":
            is_hair = du > -0.25 + 0.7 * df - 0.05 * df * df
        else:
            is_hair = du > 0.05 + 0.575 * df - 0.175 * df * df
        rgb = np.where(is_hair[..., None], hair, skin)
        for eye in eyes:
            rgb = np.where(((nx * eye[0] + ny * eye[1] + nz * eye[2]) > 0.988)[..., None], _EYE, rgb)
        # A mouth: a short horizontal line low on the front of the face.
        ds = nx * s32[0] + ny * s32[1] + nz * s32[2]
        in_mouth = (np.abs(du + 0.4) < 0.045) & (np.abs(ds) < 0.2) & (df > 0.7)
        return np.where(in_mouth[..., None], _MOUTH, rgb)

    return paint


class PerformerRenderer:
    """Draws one performer over one fixed background, frame by frame, into reused buffers.

    Args:
        look: the performer's appearance.
        background: [H, W, 3] uint8 (see :func:`clone.synth.background.make_background`).
        joint_names: names of the joints in the arrays passed to :meth:`render`, in order; the body
            is built from the motion world's joints, so every name of ``WORLD_JOINTS`` must be there.
    """

    def __init__(self, look: Look, background: np.ndarray, joint_names: Sequence[str] = WORLD_JOINTS) -> None:
        index = {n: i for i, n in enumerate(joint_names)}
        lacking = [n for n in WORLD_JOINTS if n not in index]
        if lacking:
            raise ValueError(f"renderer needs joints {', '.join(lacking)}; got {', '.join(joint_names)}")
        self.look = look
        self._j: Mapping[str, int] = index
        self._mat = Materials.of(look)
        self._ras = Rasterizer(background)
        self.width, self.height = self._ras.width, self._ras.height

    def render(self, xy: np.ndarray, depth: np.ndarray, px_per_m: float, out: np.ndarray | None = None
               ) -> np.ndarray:
        """One frame.

        Args:
            xy: [K, 2] pixel coordinates of the joints (order of ``joint_names``), NaN where missing.
            depth: [K] depth in metres, larger is farther.
            px_per_m: pixels per metre across the image.
            out: optional [H, W, 3] uint8 array to write into.

        Returns:
            [H, W, 3] uint8 RGB (``out`` when given).
        """
        self._ras.clear()
        ppm = float(px_per_m)
        xy = np.asarray(xy, dtype=np.float64)
        depth = np.asarray(depth, dtype=np.float64)
        # [K, 3] joints in metres in camera coordinates (x right, y down, z away).
        p3 = np.concatenate([xy / ppm, depth[:, None]], axis=1)
        # Far to near: with the depth test this order only matters for anti-aliased edges.
        for _, draw in sorted(self._parts(p3, ppm), key=lambda item: -item[0]):
            draw()
        return self._ras.image(out)

    def silhouette(self) -> np.ndarray:
        """[H, W] bool: pixels the body covers (at least half) in the last rendered frame."""
        return np.isfinite(self._ras.depth)

    def _ok(self, p3: np.ndarray, *names: str) -> bool:
        return all(np.isfinite(p3[self._j[n]]).all() for n in names)

    def _capsule(self, pa: np.ndarray, pb: np.ndarray, ra: float, rb: float, ppm: float, bands: Bands) -> Part:
        return 0.5 * (pa[2] + pb[2]), lambda: self._ras.capsule(pa, pb, ra, rb, ppm, bands)

    def _parts(self, p3: np.ndarray, ppm: float) -> list[Part]:
        """(mean depth, draw callable) for every body part whose joints are all present."""
        j, shape, mat = self._j, self.look.shape, self._mat
        parts: list[Part] = []
        for side in ("l", "r"):
            parts.extend(self._arm(p3, ppm, side))
            parts.extend(self._leg(p3, ppm, side))
        if self._ok(p3, "neck", "head"):
            parts.append(self._capsule(p3[j["neck"]], p3[j["head"]], shape.neck_radius, shape.neck_radius * 0.9,
                                       ppm, ((1.0, mat.skin),)))
        if self._ok(p3, "l_shoulder", "r_shoulder", "l_hip", "r_hip"):
            forward = self._forward(p3)
            parts.append(self._torso(p3, ppm, forward))
            if self.look.bottom_style == "skirt" and self._ok(p3, "l_knee", "r_knee"):
                parts.append(self._skirt(p3, ppm, forward))
        if self._ok(p3, "head", "neck"):
            parts.extend(self._head(p3, ppm))
        return parts

    def _arm(self, p3: np.ndarray, ppm: float, side: str) -> list[Part]:
        """Upper arm, forearm and hand of one side (``"l"`` or ``"r"``)."""
        j, shape, mat = self._j, self.look.shape, self._mat
        sh, el, wr = f"{side}_shoulder", f"{side}_elbow", f"{side}_wrist"
        parts: list[Part] = []
        if self._ok(p3, sh, el):
            parts.append(self._capsule(p3[j[sh]], p3[j[el]], *shape.upper_arm, ppm, mat.upper_arm))
        if self._ok(p3, el, wr):
            parts.append(self._capsule(p3[j[el]], p3[j[wr]], *shape.forearm, ppm, mat.forearm))
            direction = _unit(p3[j[wr]] - p3[j[el]], _UP)
            tip = p3[j[wr]] + direction * shape.hand_length
            parts.append(self._capsule(p3[j[wr]] + direction * 0.01, tip, shape.hand_radius,
                                       shape.hand_radius * 0.8, ppm, ((1.0, mat.skin),)))
        return parts

    def _leg(self, p3: np.ndarray, ppm: float, side: str) -> list[Part]:
        """Thigh, shin and foot of one side (``"l"`` or ``"r"``)."""
        j, shape, mat = self._j, self.look.shape, self._mat
        hip, kn, an, toe = f"{side}_hip", f"{side}_knee", f"{side}_ankle", f"{side}_big_toe"
        parts: list[Part] = []
        if self._ok(p3, hip, kn):
            # Start a little down the thigh so its round top does not bulge out of the pelvis.
            start = p3[j[hip]] + 0.12 * (p3[j[kn]] - p3[j[hip]])
            parts.append(self._capsule(start, p3[j[kn]], *shape.thigh, ppm, mat.thigh))
        if self._ok(p3, kn, an):
            parts.append(self._capsule(p3[j[kn]], p3[j[an]], *shape.shin, ppm, mat.shin))
        if self._ok(p3, an, toe):
            direction = _unit(p3[j[toe]] - p3[j[an]], -_UP)
            heel = p3[j[an]] - direction * shape.heel
            parts.append(self._capsule(heel, p3[j[toe]], shape.foot_radius * 1.1, shape.foot_radius * 0.8, ppm,
                                       ((1.0, mat.shoes),)))
        return parts

    def _forward(self, p3: np.ndarray) -> np.ndarray:
        """[3] unit vector the chest faces, from the shoulder line and the spine, signed by the nose."""
        j = self._j
        left = p3[j["l_shoulder"]] - p3[j["r_shoulder"]] + p3[j["l_hip"]] - p3[j["r_hip"]]
        spine = _unit(0.5 * (p3[j["l_shoulder"]] + p3[j["r_shoulder"]] - p3[j["l_hip"]] - p3[j["r_hip"]]), _UP)
        forward = _unit(np.cross(left, spine), np.array([0.0, 0.0, -1.0]))
        nose_dir = p3[j["nose"]] - p3[j["neck"]]
        if np.isfinite(nose_dir).all() and float(np.dot(forward, nose_dir)) < 0:
            forward = -forward
        return forward

    def _torso(self, p3: np.ndarray, ppm: float, forward: np.ndarray) -> Part:
        """The torso from the shoulders to the hips: shirt with a V-neck at the front, then belt and bottom."""
        j, shape, mat = self._j, self.look.shape, self._mat
        ls, rs, lh, rh = (p3[j[n]] for n in ("l_shoulder", "r_shoulder", "l_hip", "r_hip"))
        top, bottom = 0.5 * (ls + rs), 0.5 * (lh + rh)
        spine2 = _unit(bottom[:2] - top[:2], np.array([0.0, 1.0]))
        perp = np.array([-spine2[1], spine2[0]])
        lat_s = _unit(ls - rs, np.array([1.0, 0.0, 0.0]))
        lat_h = _unit(lh - rh, lat_s)
        # Make the lateral axes perpendicular to the forward direction so the section is a true ellipse.
        lat_s = _unit(lat_s - forward * np.dot(lat_s, forward), lat_s)
        lat_h = _unit(lat_h - forward * np.dot(lat_h, forward), lat_h)
        lat_w = _unit(lat_s + lat_h, lat_s)
        a_s = 0.5 * float(np.linalg.norm(ls - rs)) + shape.shoulder_pad
        a_h = 0.5 * float(np.linalg.norm(lh - rh)) + shape.hip_pad
        stations = (
            (0.0, _section(a_s, lat_s, shape.chest_depth * 0.85, forward, perp)),
            (0.22, _section(a_s * 0.97, lat_s, shape.chest_depth, forward, perp)),
            (0.62, _section(shape.waist * 0.5 * (a_s + a_h), lat_w, 0.5 * (shape.chest_depth + shape.hip_depth),
                            forward, perp)),
            (1.0, _section(a_h, lat_h, shape.hip_depth, forward, perp)),
        )
        shirt, belt, bottom_paint, skin = mat.shirt, mat.belt, mat.bottom, mat.skin
        skirt = self.look.bottom_style == "skirt"

        def paint(t: np.ndarray, u: np.ndarray, phi: np.ndarray, half: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
            around = phi * (0.5 * (half[0] + half[1]))  # arc length, metres
            rgb = np.where((t < 0.76)[..., None], shirt.colours(u, around),
                           np.where((t < 0.82)[..., None], belt.base, (belt if skirt else bottom_paint).base))
            # A V-neck on the front only: from the top of the chest down to a point.
            front = np.abs(phi - np.float32(np.pi / 2)) * half[0]
            vneck = (front < 0.035 - 0.55 * np.maximum(u, 0.0)) & (phi > 0)
            return np.where(vneck[..., None], skin.base, rgb)

        return (0.5 * (top[2] + bottom[2]),
                lambda: self._ras.trunk(top, bottom, stations, (0.09, 0.06), ppm, paint))

    def _skirt(self, p3: np.ndarray, ppm: float, forward: np.ndarray) -> Part:
        """A skirt from the hips to above the knees, flaring out, with pleats."""
        j, shape, mat = self._j, self.look.shape, self._mat
        lh, rh, lk, rk = (p3[j[n]] for n in ("l_hip", "r_hip", "l_knee", "r_knee"))
        top = 0.5 * (lh + rh)
        knees = 0.5 * (lk + rk)
        bottom = top + 0.85 * (knees - top)
        spine2 = _unit(bottom[:2] - top[:2], np.array([0.0, 1.0]))
        perp = np.array([-spine2[1], spine2[0]])
        lat = _unit(lh - rh, np.array([1.0, 0.0, 0.0]))
        lat = _unit(lat - forward * np.dot(lat, forward), lat)
        a_h = 0.5 * float(np.linalg.norm(lh - rh)) + shape.hip_pad
        a_k = max(0.5 * float(np.linalg.norm(lk - rk)) + shape.thigh[1] * 1.6, a_h * 1.25)
        stations = (
            (0.0, _section(a_h * 1.02, lat, shape.hip_depth * 1.05, forward, perp)),
            (1.0, _section(a_k, lat, shape.hip_depth * 1.5, forward, perp)),
        )
        paint_skirt = mat.bottom

        def paint(t: np.ndarray, u: np.ndarray, phi: np.ndarray, half: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
            # Pleats: a gentle light/dark modulation around the skirt.
            pleat = 1.0 + 0.07 * np.sin(phi * 9.0)
            return paint_skirt.base * pleat[..., None]

        return (0.5 * (top[2] + bottom[2]), lambda: self._ras.trunk(top, bottom, stations, (0.02, 0.0), ppm, paint))

    def _head(self, p3: np.ndarray, ppm: float) -> list[Part]:
        """Long hair (behind the head), the nose and the head itself, turned the way the nose points."""
        j, shape, mat, look = self._j, self.look.shape, self._mat, self.look
        centre, neck = p3[j["head"]], p3[j["neck"]]
        up = _unit(centre - neck, _UP)
        nose = p3[j["nose"]]
        face = nose - centre if np.isfinite(nose).all() else np.array([0.0, 0.0, -1.0])
        face = face - up * np.dot(face, up)
        face = _unit(face, _unit(np.array([0.0, 0.0, -1.0]) - up * -up[2], np.array([0.0, 0.0, -1.0])))
        hr = shape.head_radius
        parts: list[Part] = []
        if look.hair_style == "long":
            # Long hair: a tapering mass behind the head down to the shoulders.
            start = centre - face * hr * 0.35 + up * hr * 0.1
            end = neck - face * hr * 0.75 + up * hr * 0.2
            parts.append(self._capsule(start, end, hr * 1.02, hr * 0.85, ppm, ((1.0, mat.hair),)))
        paint = _face_paint(face, up, np.cross(up, face), look.hair_style, mat.skin.base, mat.hair.base)
        if np.isfinite(nose).all():
            # The nose: a small skin capsule from inside the face out to the nose point.
            root = centre + face * hr * 0.6 - up * hr * 0.15
            parts.append((float(nose[2]), lambda: self._ras.capsule(root, nose, hr * 0.2, hr * 0.16, ppm,
                                                                     ((1.0, mat.skin),))))
        # Taller than wide, reaching further down (jaw) than up (the skull's centre is above the face's).
        chin, crown = centre - up * hr * 0.45, centre + up * hr * 0.2
        parts.append((float(centre[2]), lambda: self._ras.ellipsoid(chin, crown, hr, ppm, paint)))
        return parts
