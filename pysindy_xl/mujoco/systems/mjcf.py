"""A user's MJCF model as a system: coordinates are MuJoCo's joint coordinates."""

from __future__ import annotations

import keyword
import os
import re

import numpy as np

from ..._optional import import_mujoco
from .base import MuJoCoSystem, checked_parameters
from .urdf import is_urdf, urdf_spec

__all__ = ["MJCFSystem"]


# -- user-supplied models ------------------------------------------------------------------
def _identifier(name: str, index: int, taken: set) -> str:
    ident = re.sub(r"\W", "_", name or "") or f"q{index}"
    if ident[0].isdigit() or keyword.iskeyword(ident) or ident == "t":
        ident = f"q_{ident}"
    if ident.startswith("tau_") or ident.endswith(("_dot", "_ddot")):
        ident = f"{ident}_q"
    base, k = ident, 1
    while ident in taken:
        ident, k = f"{base}_{k}", k + 1
    taken.add(ident)
    return ident


class MJCFSystem(MuJoCoSystem):
    """A user's MJCF model: coordinates are MuJoCo's joint coordinates.

    Hinge and slide joints only (``q = qpos``); hinges count as angles for the catalogs. The
    true Lagrangian is unknown; joint damping is read from the model as diagonal friction.

    Parameters
    ----------
    source : str or os.PathLike
        Path to an MJCF or URDF (``.urdf``) file, or the text itself (starting with ``<``); a
        URDF as read by :mod:`pysindy_xl.mujoco.systems.urdf`.
    force_amplitude : float, default 1.0
        Amplitude of the random force of an actuator without ``ctrlrange``.
    joints : list of str, optional
        Identify these joints only; the others are locked at their reference pose (removed
        with their actuators, ``excluded_joints``; their bodies load their parents).

    Examples
    --------
    Leave a passive target on two slide joints out:

    >>> xml = '''<mujoco><worldbody>
    ... <body><joint name="swing" axis="0 1 0"/><geom size="0.1" pos="0 0 -1"/></body>
    ... <body pos="2 0 0"><joint name="tx" type="slide" axis="1 0 0"/>
    ... <joint name="ty" type="slide" axis="0 1 0"/><geom size="0.1"/></body>
    ... </worldbody></mujoco>'''
    >>> system = MJCFSystem(xml, joints=["swing"])
    >>> system.coords, system.excluded_joints, system.mj_model().nq
    (Coordinates(['swing']), ('tx', 'ty'), 1)
    """

    name = "mjcf"
    has_ground_truth = False

    def __init__(self, source, force_amplitude=1.0, joints=None):
        mujoco = import_mujoco()
        self._urdf = is_urdf(source)
        if isinstance(source, os.PathLike) or (isinstance(source, str)
                                               and not source.lstrip().startswith("<")):
            path = os.fspath(source)
            if not os.path.isfile(path):
                raise ValueError(f"source: {'URDF' if self._urdf else 'MJCF'} file {path!r} "
                                 "does not exist")
            with open(path, encoding="utf-8") as handle:
                self._xml = handle.read()
            if self._urdf:
                self._urdf_text = self._xml
                spec = urdf_spec(self._xml, f"source {path!r}")
                model, self._xml = spec.compile(), spec.to_xml()
            else:
                try:
                    model = mujoco.MjModel.from_xml_path(path)
                except ValueError as error:
                    raise ValueError(f"source: cannot load MJCF file {path!r}: {error}") \
                        from None
            self.path = os.path.abspath(path)
        elif isinstance(source, str) and self._urdf:
            spec, self._urdf_text, self.path = urdf_spec(source), source, None
            model, self._xml = spec.compile(), spec.to_xml()
        elif isinstance(source, str):
            try:
                model = mujoco.MjModel.from_xml_string(source)
            except ValueError as error:
                raise ValueError(f"source: cannot compile MJCF text: {error}") from None
            self._xml, self.path = source, None
        else:
            raise TypeError(f"source: expected a path or MJCF text, got {type(source).__name__}")
        allowed = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        if model.njnt == 0:
            raise ValueError("source: the model has no joint, nothing to identify")
        for j in range(model.njnt):
            if int(model.jnt_type[j]) not in allowed:
                jname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"#{j}"
                raise ValueError(f"source: joint {jname!r} is not a hinge or slide joint; only "
                                 "those are supported (one coordinate per joint)")
        self._spec = None
        self.excluded_joints = ()
        self.trimmed_keyframes = ()
        if joints is not None:
            model = self._select_joints(model, joints)
        self._model = model
        taken: set = set()
        raw = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or "" for j in
               range(model.njnt)]
        self.joint_names = tuple(raw[j] or f"joint{j}" for j in range(model.njnt))
        self.coordinate_names = tuple(_identifier(raw[j], j, taken) for j in range(model.njnt))
        hinge = int(mujoco.mjtJoint.mjJNT_HINGE)
        self.angle_coordinates = tuple(j for j in range(model.njnt)
                                       if int(model.jnt_type[j]) == hinge)
        self.mixed_actuators = self.actuated_joints[:1]
        self._parameters = {"source": self.path or "<string>",
                            **checked_parameters(force_amplitude=force_amplitude),
                            "timestep": float(model.opt.timestep)}
        if joints is not None:
            self._parameters["joints"] = list(self.joint_names)

    def _select_joints(self, model, joints):
        try:
            joints = [joints] if isinstance(joints, str) else list(joints)
        except TypeError:
            raise TypeError(f"joints: expected a list of joint names, got {joints!r}") from None
        mujoco = import_mujoco()
        names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
                 for j in range(model.njnt)]
        unknown = [j for j in joints if j not in names]
        if unknown or not joints or not all(isinstance(j, str) for j in joints):
            raise ValueError(f"joints: expected a non-empty list of joint names among {names}, "
                             f"got {joints!r}")
        if not hasattr(mujoco, "MjSpec"):
            raise ValueError(f"joints: selecting joints needs MuJoCo >= 3.3 (MjSpec), found "
                             f"{mujoco.__version__}")
        spec = (self._urdf_spec() if self._urdf else mujoco.MjSpec.from_file(self.path)
                if self.path is not None else mujoco.MjSpec.from_string(self._xml))
        excluded = [name for name in names if name not in joints]
        kept_actuators = [spec_actuator.target not in excluded
                          for spec_actuator in spec.actuators]
        for name in excluded:
            joint = spec.joint(name)
            if joint is None:
                raise ValueError(f"joints: cannot lock the unnamed joint {name!r}; name it")
            for actuator in list(spec.actuators):
                if actuator.target == name:
                    spec.delete(actuator)
            spec.delete(joint)
        # a joint coupling to a locked joint (a URDF mimic joint: a gripper's second finger)
        # goes with it
        for equality in list(spec.equalities):
            if equality.type == mujoco.mjtEq.mjEQ_JOINT and (
                    equality.name1 in excluded or equality.name2 in excluded):
                spec.delete(equality)
        self.trimmed_keyframes = _trim_keyframes(spec, [name in joints for name in names],
                                                 kept_actuators)
        self._spec, self.excluded_joints = spec, tuple(excluded)
        try:
            return spec.compile()
        except ValueError as error:
            raise ValueError(f"joints: the model with {excluded} locked does not compile: "
                             f"{error}") from None

    @property
    def frictionloss(self) -> np.ndarray:
        """Dry friction (``frictionloss``) of each joint, shape (n,).

        >>> xml = ('<mujoco><worldbody><body><joint type="slide" frictionloss="0.3"/>'
        ...        '<geom size="0.1"/></body></worldbody></mujoco>')
        >>> MJCFSystem(xml).frictionloss
        array([0.3])
        """
        model = self._model
        return np.array([model.dof_frictionloss[model.jnt_dofadr[j]] for j in range(model.njnt)],
                        dtype=float)

    def random_initial_state(self, rng: np.random.Generator, scale: float = 1.0):
        """Random initial state inside the joint ranges, around the reference pose.

        A joint with a range starts uniformly between its ``ref`` (clipped to the range) and
        ``scale`` x 90 % of the way to each end, with a velocity of at most ``scale`` x
        min(1, half the range width) per second; a joint without range as in
        :meth:`MuJoCoSystem.random_initial_state`, around ``ref``.

        Parameters
        ----------
        rng : numpy.random.Generator
            The random generator.
        scale : float, default=1.0
            Fraction of the range (or of the default spread) used.

        Returns
        -------
        q0 : numpy.ndarray of shape (n,)
            Initial joint positions.
        qd0 : numpy.ndarray of shape (n,)
            Initial joint velocities.

        Examples
        --------
        >>> xml = ('<mujoco><compiler angle="radian"/><worldbody><body>'
        ...        '<joint type="slide" range="0 0.2" ref="0.05"/><geom size="0.1"/>'
        ...        '</body></worldbody></mujoco>')
        >>> q0 = np.array([MJCFSystem(xml).random_initial_state(np.random.default_rng(k))[0]
        ...                for k in range(200)])
        >>> bool(q0.min() >= 0.0 and q0.max() <= 0.2)
        True
        """
        model = self._model
        ref = np.array([model.qpos0[model.jnt_qposadr[j]] for j in range(model.njnt)])
        limited = np.asarray(model.jnt_limited, dtype=bool)
        low, high = np.asarray(model.jnt_range, dtype=float).T
        half = np.full(self.n, 0.5)
        half[list(self.angle_coordinates)] = 2.0
        draw = rng.uniform(-1.0, 1.0, self.n)
        center = np.where(limited, np.clip(ref, low, high), ref)
        reach = np.where(draw > 0, high - center, center - low)
        q0 = np.where(limited, center + 0.9 * scale * draw * reach, ref + draw * half * scale)
        margin = 0.05 * (high - low)
        q0 = np.where(limited, np.clip(q0, low + margin, high - margin), q0)
        speed = np.where(limited, np.minimum(1.0, (high - low) / 2), 1.0)
        return q0, rng.uniform(-1.0, 1.0, self.n) * speed * scale

    def metadata(self) -> dict:
        """What a dataset records to rebuild this system (:func:`system_from_metadata`).

        ``model_path`` (absolute, or None), ``model_xml`` (the MJCF text, flattened when it
        uses ``<include>``) and ``joints`` (None for every joint).

        Returns
        -------
        dict
            ``{"model_path": ..., "model_xml": ..., "joints": ...}``.
        """
        text = self._xml
        if "<include " in text and self.path is not None and not self._urdf:
            text = import_mujoco().MjSpec.from_file(self.path).to_xml()
        return {"model_path": self.path, "model_xml": text,
                "joints": self._parameters.get("joints")}

    @property
    def actuated_joints(self):
        model, joint = self._model, int(import_mujoco().mjtTrn.mjTRN_JOINT)
        return tuple(dict.fromkeys(self.joint_names[model.actuator_trnid[a, 0]] for a in
                                   range(model.nu) if int(model.actuator_trntype[a]) == joint))

    @property
    def joint_damping(self):
        return np.array([self._model.dof_damping[self._model.jnt_dofadr[j]]
                         for j in range(self._model.njnt)], dtype=float)

    @property
    def force_amplitudes(self):
        return {j: self._parameters["force_amplitude"] for j in self.actuated_joints}

    def lagrangian(self):
        """Not available: raises NotImplementedError (subclass :class:`MuJoCoSystem` to give a
        model a known Lagrangian)."""
        raise NotImplementedError("MJCFSystem: the true Lagrangian of a user's model is "
                                  "unknown; subclass MuJoCoSystem to provide one")

    def xml(self):
        """The MJCF text given (or read from the file given); with ``joints``, the reduced model.

        Returns
        -------
        str
            The MJCF document.
        """
        return self._xml if self._spec is None else self._spec.to_xml()

    def mj_model(self):
        """Compiled MuJoCo model, from the file when one was given (relative assets resolve).

        Returns
        -------
        mujoco.MjModel
            The compiled model (a new object at each call).
        """
        mujoco = import_mujoco()
        if self._spec is not None:
            return self._spec.compile()
        if self._urdf:  # from the URDF's own numbers (the MJCF text rounds them)
            return self._urdf_spec().compile()
        if self.path is not None:
            return mujoco.MjModel.from_xml_path(self.path)
        return mujoco.MjModel.from_xml_string(self._xml)

    def _urdf_spec(self):
        return urdf_spec(self._urdf_text, warn=False)

    def __repr__(self):
        return f"MJCFSystem({self._parameters['source']!r})"


def _trim_keyframes(spec, kept_joints, kept_actuators) -> tuple:
    """Cut every keyframe to the kept joints and actuators (a keyframe sized for the whole
    model would not compile); activations of removed actuators cleared. Names of those changed."""
    kept_joints = np.asarray(kept_joints, dtype=bool)
    kept_actuators = np.asarray(kept_actuators, dtype=bool)
    trimmed = []
    for key in spec.keys:
        changed = False
        for field, kept in (("qpos", kept_joints), ("qvel", kept_joints),
                            ("ctrl", kept_actuators)):
            values = np.asarray(getattr(key, field), dtype=float)
            if values.size == kept.size and not kept.all():
                setattr(key, field, values[kept].tolist())
                changed = True
        if len(key.act) and not kept_actuators.all():
            key.act = []
            changed = True
        if changed:
            trimmed.append(key.name or f"key {len(trimmed)}")
    return tuple(trimmed)
