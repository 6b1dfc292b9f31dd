"""Choosing the arm and torso joints of a skeleton rig (BVH joints or ASF bones)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from visprim.io.errors import MissingPointError
from visprim.io.presets import (
    ARM_ROLES,
    RIG_PRESETS,
    RIG_TORSO_ROLES,
    NameIndex,
    fill_side,
    normalise_mapping,
)

_RIG_ROLES = (*ARM_ROLES, "finger", *RIG_TORSO_ROLES)


@dataclass(frozen=True)
class RigRoles:
    """Resolved joint indices per role (``None``: the rig does not have it)."""

    preset: str
    index: dict[str, int | None]
    names: dict[str, str | None]

    def has(self, *roles: str) -> bool:
        return all(self.index.get(r) is not None for r in roles)


def _lookup(
    idx: NameIndex, candidates: Sequence[str], arm: str, path: str
) -> tuple[int | None, str | None]:
    for cand in candidates:
        name = fill_side(cand, arm)
        try:
            i = idx.find(name)
        except LookupError as exc:
            raise MissingPointError(path, str(exc)) from None
        if i is not None:
            return i, idx.names[i]
    return None, None


def resolve_rig(
    path: str,
    names: Sequence[str],
    arm: str,
    preset: str | None = None,
    mapping: Mapping[str, str | Sequence[str]] | None = None,
    *,
    kind: str = "joint",
) -> RigRoles:
    """Find the joints of each role for ``arm`` ('right' or 'left').

    ``mapping`` (role → name or candidate names) overrides the preset's roles; without a
    ``preset`` the first preset of :data:`~visprim.io.presets.RIG_PRESETS` whose shoulder,
    elbow and wrist are all present is used. Raises :class:`MissingPointError` naming the
    missing joints when the arm cannot be found.
    """
    idx = NameIndex(names)
    user = normalise_mapping(mapping) if mapping else {}
    unknown = set(user) - set(_RIG_ROLES)
    if unknown:
        raise ValueError(
            f"mapping has unknown role(s) {sorted(unknown)}; roles are {', '.join(_RIG_ROLES)}"
        )
    if preset is not None and preset not in RIG_PRESETS:
        raise ValueError(f"unknown rig preset {preset!r}; known: {', '.join(RIG_PRESETS)}")

    def attempt(roles: Mapping[str, Sequence[str]]) -> tuple[dict[str, int | None], list[str]]:
        merged = {**roles, **user}
        found: dict[str, int | None] = {}
        missing = []
        for role in _RIG_ROLES:
            i, _ = _lookup(idx, merged.get(role, []), arm, path)
            found[role] = i
            if role in ARM_ROLES and i is None:
                tried = [fill_side(c, arm) for c in merged.get(role, [])]
                missing.append(f"{role} ({' or '.join(tried) or 'no name given'})")
        return found, missing

    if preset is not None:
        candidates = [preset]
    elif user and all(r in user for r in ARM_ROLES):
        candidates = ["mapping", *RIG_PRESETS]
    else:
        candidates = list(RIG_PRESETS)
    report = []
    for name in candidates:
        roles = {} if name == "mapping" else RIG_PRESETS[name].roles
        found, missing = attempt(roles)
        if not missing:
            if name == "mapping":
                # Borrow torso roles from a preset that matches, if any.
                for other in RIG_PRESETS:
                    extra, miss = attempt(RIG_PRESETS[other].roles)
                    if not miss:
                        for role in RIG_TORSO_ROLES:
                            if role not in user:
                                found[role] = extra[role]
                        break
            return RigRoles(
                preset=name,
                index=found,
                names={r: (names[i] if i is not None else None) for r, i in found.items()},
            )
        report.append(f"{name}: missing {', '.join(missing)}")
    sample = ", ".join(list(names)[:12]) + (" ..." if len(names) > 12 else "")
    raise MissingPointError(
        path,
        f"cannot find the {arm} arm's {kind}s; tried "
        + "; ".join(report)
        + f". The file's {kind}s: {sample}. Pass mapping={{'shoulder': ..., 'elbow': ..., "
        "'wrist': ...}} to name them.",
    )
