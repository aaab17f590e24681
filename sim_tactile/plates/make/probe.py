"""What MuJoCo's collider sees: surface heights probed with a small sphere.

docs/physics.md: ``mj_ray`` and rendering see a mesh's triangles while collision sees its convex
hull, so collision geometry must be validated with ``mj_geomDistance``. A probe sphere of
radius ``r`` above (x, y) is lowered by the signed distance to the nearest plate geom until
it touches ("sphere tracing": a step never passes through a surface, because the distance is
the smallest in any direction); the surface height is then the centre height minus ``r``.
On a slope of angle a the result is high by r (1/cos a - 1), which is negligible for the
default r = 1 um.
"""

from __future__ import annotations

import mujoco
import numpy as np

from ...errors import GeometryError

#: Default probe radius [m].
PROBE_RADIUS_M = 1e-6
#: Sphere tracing stops when the probe is this close to the surface [m].
TOUCH_TOL_M = 1e-9
_MAX_STEPS = 200
_HFIELD_CONTACT_CAP = 50


class ColliderProbe:
    """Probe the collision geometry of body ``plate`` in an MJCF (text or MjSpec)."""

    def __init__(
        self,
        mjcf: str | mujoco.MjSpec,
        *,
        radius_m: float = PROBE_RADIUS_M,
        z_start_m: float = 0.02,
    ):
        spec = mujoco.MjSpec.from_string(mjcf) if isinstance(mjcf, str) else mjcf.copy()
        body = spec.worldbody.add_body(name="probe", mocap=True)
        body.add_geom(
            name="probe",
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            size=(radius_m, 0, 0),
            contype=0,
            conaffinity=0,
        )
        # mj_geomDistance does not handle height fields: probe those through the collider
        # itself, with an explicit contact pair whose margin reports nearby distances. The
        # margin must stay small: MuJoCo keeps at most 50 contacts per hfield pair, filled in
        # row order, so a wide margin returns far cells and misses the near one.
        self._hf_margin = np.inf
        self._hf_top = -np.inf
        for g in spec.geoms:
            if g.type == mujoco.mjtGeom.mjGEOM_HFIELD:
                hf = spec.hfield(g.hfieldname)
                cell = 2 * hf.size[0] / (hf.ncol - 1)
                # cells within the margin lie within sqrt(2 r margin) of the probe's axis:
                # keep that to about 8 cells, well under the cap
                margin = min(4 * cell, (8 * cell) ** 2 / (2 * radius_m))
                self._hf_margin = min(self._hf_margin, margin)
                self._hf_top = max(self._hf_top, g.pos[2] + hf.size[2])
                spec.add_pair(geomname1="probe", geomname2=g.name, margin=margin)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.radius_m = radius_m
        self.z_start_m = z_start_m
        self._probe = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "probe")
        plate = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "plate")
        if plate < 0:
            raise GeometryError("the MJCF has no body named 'plate'")
        mujoco.mj_kinematics(m, self.data)
        self._geoms = np.array([g for g in range(m.ngeom) if m.geom_bodyid[g] == plate])
        # axis-aligned xy bounds of each geom (rbound is the bounding-sphere radius)
        self._xy = self.data.geom_xpos[self._geoms, :2].copy()
        self._rb = m.geom_rbound[self._geoms].copy()
        self._rb[self._rb == 0] = np.inf  # planes
        is_hf = m.geom_type[self._geoms] == mujoco.mjtGeom.mjGEOM_HFIELD
        self._hfields = self._geoms[is_hf]
        self._geoms, self._xy, self._rb = self._geoms[~is_hf], self._xy[~is_hf], self._rb[~is_hf]

    def _dist(self, x: float, y: float, z: float) -> float:
        m, d = self.model, self.data
        d.mocap_pos[0] = (x, y, z)
        mujoco.mj_kinematics(m, d)
        near = np.abs(self._xy - (x, y)).max(axis=1) <= self._rb + self.radius_m
        best = np.inf
        for g in self._geoms[near]:
            best = min(best, mujoco.mj_geomDistance(m, d, self._probe, int(g), 1.0, None))
        if len(self._hfields):
            mujoco.mj_collision(m, d)  # geom poses are current from mj_kinematics above
            if d.ncon >= _HFIELD_CONTACT_CAP:
                raise GeometryError(
                    f"probe at ({x:g}, {y:g}) hit MuJoCo's cap of {_HFIELD_CONTACT_CAP} "
                    "contacts per height-field pair; use a smaller probe radius"
                )
            for c in d.contact[: d.ncon]:
                best = min(best, float(c.dist))
            # a field farther than the margin is not reported: never step past the margin
            best = min(best, 0.5 * self._hf_margin)
        return best

    def height(self, x: float, y: float) -> float:
        """Surface height under (x, y) [m]; NaN if nothing is below the probe."""
        z = self.z_start_m
        if len(self._hfields):
            z = min(z, self._hf_top + self.radius_m + 0.5 * self._hf_margin)
        for _ in range(_MAX_STEPS):
            dist = self._dist(x, y, z)
            if not np.isfinite(dist) or dist >= 1.0:
                return float("nan")
            if dist <= TOUCH_TOL_M:
                return z - self.radius_m
            z -= dist
        return z - self.radius_m  # near a vertical wall tracing creeps; report where it got

    def heights(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Vectorised :meth:`height` over broadcast ``x``, ``y`` [m]."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        out = np.array([self.height(a, b) for a, b in zip(x.ravel(), y.ravel(), strict=True)])
        return out.reshape(x.shape)
