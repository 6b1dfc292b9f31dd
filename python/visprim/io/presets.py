"""Joint- and marker-name presets: which points of a file are the arm and the torso.

Skeleton rigs (BVH joints, ASF bones) use :class:`RigPreset`; marker sets (C3D) use
:class:`MarkerPreset`. Names may contain side placeholders filled from the requested arm:
``{S}`` → ``R``/``L``, ``{s}`` → ``r``/``l``, ``{Side}`` → ``Right``/``Left``. Every role
lists candidate names; the first one present in the file is used. Names are matched exactly
first, then ignoring case and any namespace prefix ending in ``:`` (``mixamorig:RightArm``,
``Derrick:RSHO``).

Roles (skeletons): ``shoulder``, ``elbow``, ``wrist`` — joints whose origin is that joint
centre (for ASF: the bone whose *start* is at the joint); ``finger`` — the middle finger's
knuckle (metacarpophalangeal joint) when the rig has it; ``chest`` — the joint whose rotation
carries the torso; ``trunk_low``/``trunk_high`` (a point low and high on the spine) and
``lateral_right``/``lateral_left`` (a point on each side of the chest) define the torso axes.

Roles (markers): ``shoulder`` (a joint centre) or ``acromion`` (a surface landmark, offset
down to the shoulder centre), ``elbow`` and ``wrist`` (the centroid of the listed markers,
e.g. both epicondyles / both styloids), ``finger``, optional ``upper_arm``/``forearm``
(the file's own sensors, for ``markers="file"``) and torso markers ``up_low``/``up_high``
(low and high on the thorax), ``back``/``front``, ``lateral_right``/``lateral_left``;
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

#: Placeholder values for each arm.
SIDE_TOKENS: dict[str, dict[str, str]] = {
    "right": {"S": "R", "s": "r", "Side": "Right"},
    "left": {"S": "L", "s": "l", "Side": "Left"},
}

ARM_ROLES: tuple[str, ...] = ("shoulder", "elbow", "wrist")
RIG_TORSO_ROLES: tuple[str, ...] = (
    "chest",
    "trunk_low",
    "trunk_high",
    "lateral_right",
    "lateral_left",
)
MARKER_ROLES: tuple[str, ...] = (
    "shoulder",
    "acromion",
    "elbow",
    "wrist",
    "finger",
    "upper_arm",
    "forearm",
    "up_low",
    "up_high",
    "back",
    "front",
    "lateral_right",
    "lateral_left",
)


@dataclass(frozen=True)
class RigPreset:
    """Names of the arm and torso joints of a skeleton rig (BVH or ASF).

    Each role maps to candidate names (first present wins). An empty ``finger`` list means
    the rig has no finger joint: the finger point is then extrapolated from the hand joint
    (see :func:`visprim.io.skeleton.extend_hand`).
    """

    name: str
    roles: Mapping[str, Sequence[str]]
    description: str = ""


@dataclass(frozen=True)
class MarkerPreset:
    """Names of the arm landmarks and torso markers of a marker set (C3D)."""

    name: str
    roles: Mapping[str, Sequence[str]]
    description: str = ""
    #: Roles whose markers are averaged (centroid) instead of taking the first present.
    centroid_roles: frozenset[str] = field(
        default_factory=lambda: frozenset(
            {"elbow", "wrist", "finger", "upper_arm", "forearm", "up_low", "up_high"}
            | {"back", "front", "lateral_right", "lateral_left"}
        )
    )


RIG_PRESETS: dict[str, RigPreset] = {
    "bandai": RigPreset(
        "bandai",
        {
            "shoulder": ["UpperArm_{S}"],
            "elbow": ["LowerArm_{S}"],
            "wrist": ["Hand_{S}"],
            "finger": [],
            "chest": ["Chest"],
            "trunk_low": ["Hips"],
            "trunk_high": ["Neck"],
            "lateral_right": ["UpperArm_R"],
            "lateral_left": ["UpperArm_L"],
        },
        "Bandai-Namco Research Motiondataset (22 joints, no finger joint)",
    ),
    "cc3": RigPreset(
        "cc3",
        {
            "shoulder": ["CC_Base_{S}_Upperarm"],
            "elbow": ["CC_Base_{S}_Forearm"],
            "wrist": ["CC_Base_{S}_Hand"],
            "finger": ["CC_Base_{S}_Mid1"],
            "chest": ["CC_Base_Spine02", "CC_Base_Spine01"],
            "trunk_low": ["CC_Base_Hip", "CC_Base_Pelvis"],
            "trunk_high": ["CC_Base_NeckTwist01", "CC_Base_Head"],
            "lateral_right": ["CC_Base_R_Upperarm"],
            "lateral_left": ["CC_Base_L_Upperarm"],
        },
        "Reallusion Character Creator 3 / iClone CC_Base rig (CMU re-exports)",
    ),
    "mixamo": RigPreset(
        "mixamo",
        {
            "shoulder": ["{Side}Arm", "{Side}UpperArm"],
            "elbow": ["{Side}ForeArm", "{Side}LowerArm"],
            "wrist": ["{Side}Hand"],
            "finger": ["{Side}HandMiddle1", "{Side}MiddleProximal", "{Side}FingerBase"],
            "chest": ["Spine2", "Chest", "Spine1", "Spine"],
            "trunk_low": ["Hips"],
            "trunk_high": ["Neck", "Neck1", "Head"],
            "lateral_right": ["RightArm", "RightUpperArm"],
            "lateral_left": ["LeftArm", "LeftUpperArm"],
        },
        "Mixamo-style names (mixamorig:RightArm ...), also CMU 'cgspeed' BVH and Unity-like rigs",
    ),
    "cmu_asf": RigPreset(
        "cmu_asf",
        {
            "shoulder": ["{s}humerus"],
            "elbow": ["{s}radius"],
            # The CMU 'wrist' bone continues the forearm (its one DOF twists about the
            # forearm axis); the radiocarpal joint is at the start of the 'hand' bone.
            "wrist": ["{s}hand"],
            "finger": ["{s}fingers"],
            "chest": ["thorax"],
            "trunk_low": ["lowerback"],
            "trunk_high": ["lowerneck"],
            "lateral_right": ["rhumerus"],
            "lateral_left": ["lhumerus"],
        },
        "CMU / Vicon BodyBuilder ASF skeleton (bone starts are the joint centres)",
    ),
}

MARKER_PRESETS: dict[str, MarkerPreset] = {
    "plug_in_gait": MarkerPreset(
        "plug_in_gait",
        {
            "acromion": ["{S}SHO"],
            "elbow": ["{S}ELB"],
            "wrist": ["{S}WRA", "{S}WRB"],
            "finger": ["{S}FIN"],
            "upper_arm": ["{S}UPA"],
            "forearm": ["{S}FRM"],
            "up_low": ["T10", "STRN"],
            "up_high": ["C7", "CLAV"],
            "back": ["C7", "T10"],
            "front": ["CLAV", "STRN"],
            "lateral_right": ["RSHO"],
            "lateral_left": ["LSHO"],
        },
        "Vicon Plug-in Gait upper body (RSHO RUPA RELB RFRM RWRA RWRB RFIN; C7 T10 CLAV STRN)."
        " Only the lateral epicondyle (RELB) is marked: the elbow centre is taken there.",
    ),
    "anatomical_landmarks": MarkerPreset(
        "anatomical_landmarks",
        {
            "acromion": ["Acromion{S}"],
            "elbow": ["LateralEpicondyle{S}", "MedialEpicondyle{S}"],
            "wrist": ["RadialStyloid{S}", "UlnarStyloid{S}"],
            "finger": ["Glove{S}1", "Glove{S}2", "Glove{S}3"],
            "upper_arm": ["Arm{S}1", "Arm{S}2", "Arm{S}3"],
            "forearm": ["Forearm{S}1", "Forearm{S}2", "Forearm{S}3"],
            "lateral_right": ["ScapulaR1", "ScapulaR2", "ScapulaR3"],
            "lateral_left": ["ScapulaL1", "ScapulaL2", "ScapulaL3"],
        },
        "Probed anatomical landmarks (Kinetics Toolkit racing: AcromionR, epicondyles, styloids,"
        " glove cluster as the hand end, scapula clusters for the torso's lateral axis; no"
        " thorax markers, so the vertical is the Kinetics Toolkit / ISB convention +Y)",
    ),
    "pyomeca_upper_limb": MarkerPreset(
        "pyomeca_upper_limb",
        {
            "acromion": ["ACRO_tip"],
            "elbow": ["EPICl", "EPICm"],
            "wrist": ["STYLr", "STYLu"],
            "finger": ["INDEX"],
            "upper_arm": ["ARMl"],
            "forearm": ["LARMl"],
            "up_low": ["XIPH", "T10"],
            "up_high": ["STER", "T1"],
            "back": ["T1", "T10"],
            "front": ["STER", "XIPH"],
        },
        "IRSST / pyomeca right upper-limb set (ACRO_tip, EPICl/m, STYLr/u, INDEX; thorax STER"
        " XIPH T1 T10). Right arm only.",
    ),
}


def strip_namespace(name: str) -> str:
    """``'Derrick:RSHO'`` → ``'RSHO'``; names without ``:`` are returned unchanged."""
    return name.rsplit(":", 1)[-1].strip()


class NameIndex:
    """Looks names up exactly, then case-insensitively without namespace prefixes."""

    def __init__(self, names: Iterable[str]) -> None:
        self.names = list(names)
        self.exact = {n: i for i, n in enumerate(self.names)}
        loose: dict[str, list[int]] = {}
        for i, n in enumerate(self.names):
            loose.setdefault(strip_namespace(n).lower(), []).append(i)
        self.loose = loose

    def find(self, name: str) -> int | None:
        """Index of ``name``, or ``None``. Ambiguous loose matches (the same stripped name
        under two prefixes) raise :class:`LookupError`."""
        if name in self.exact:
            return self.exact[name]
        hits = self.loose.get(strip_namespace(name).lower(), [])
        if len(hits) > 1:
            raise LookupError(
                f"{name!r} matches several names ({', '.join(self.names[i] for i in hits)}); "
                "give the full name in `mapping`"
            )
        return hits[0] if hits else None


def fill_side(template: str, arm: str) -> str:
    """Replace the side placeholders of ``template`` for ``arm`` ('right' or 'left')."""
    out = template
    for key, value in SIDE_TOKENS[arm].items():
        out = out.replace("{" + key + "}", value)
    return out


def check_arm(arm: str) -> str:
    """Validate the ``arm`` argument ('right', 'left' or 'both', case-insensitive)."""
    value = str(arm).lower()
    if value not in SIDE_TOKENS and value != "both":
        raise ValueError(f"arm must be 'right', 'left' or 'both', got {arm!r}")
    return value


def normalise_mapping(mapping: Mapping[str, str | Sequence[str]]) -> dict[str, list[str]]:
    """A user mapping ``role -> name or names`` as ``role -> [names]``."""
    out: dict[str, list[str]] = {}
    for role, value in mapping.items():
        if isinstance(value, str):
            out[str(role)] = [value]
        else:
            names = [str(v) for v in value]
            if not names:
                raise ValueError(f"mapping[{role!r}] is empty")
            out[str(role)] = names
    return out
