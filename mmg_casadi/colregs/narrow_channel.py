"""COLREG Rule 9(a), narrow channels: the share of a ship's time in a narrow channel spent on its starboard side.

Rule 9(a): "A vessel proceeding along the course of a narrow channel or fairway shall keep as near to the outer
limit of the channel or fairway which lies on her starboard side as is safe and practicable."

**Narrow channel** (ours; the COLREGs define none). At a sample, a ship is *in a narrow channel* when the line
through her centre perpendicular to her heading meets a wall or land edge on each side, at ``d_port`` to port and
``d_stbd`` to starboard, and the channel there, ``d_port + d_stbd``, is at most the profile's ``rule9_width`` wide
(20 L; :class:`~mmg_casadi.colregs.profiles.ScoringProfile`): a
channel is water with banks (walls or land) on both sides across her track, so open water and a single coast
are not. The channel's centre line at that cross-section is the midpoint between the banks; the ship is on the
starboard side of it *for her direction of travel* when her offset ``(d_port − d_stbd) / 2`` is positive (the
starboard bank is the nearer).

**Score and verdict.** The score is the share of the ship's time in a narrow channel (while she sails) spent on the
starboard side of the centre line; the rule is kept when the share is at least the profile's ``rule9_kept_share``
(0.9). A ship that is
never in a narrow channel has no Rule 9 verdict (``None``).

Examples
--------
A channel 10 L wide along x (banks at y = ±5 L): a ship northbound (heading 0, starboard = +y) 2 L east of the
centre line keeps to starboard; 2 L west she does not.

>>> banks = [((-50.0, -5.0), (150.0, -5.0)), ((-50.0, 5.0), (150.0, 5.0))]
>>> t = np.linspace(0.0, 50.0, 51)
>>> east = np.column_stack([t, 2.0 + 0 * t])
>>> r = rule9(t, east, 0 * t, np.ones(t.size, bool), banks)
>>> r.verdict, r.score, r.terms["channel_time"]
(True, 1.0, 50.0)
>>> rule9(t, east * [1, -1], 0 * t, np.ones(t.size, bool), banks).verdict
False
>>> rule9(t, east + [0, 20], 0 * t, np.ones(t.size, bool), banks) is None  # outside the channel
True
"""

from __future__ import annotations

import numpy as np

from mmg_casadi.colregs.profiles import scoring_profile
from mmg_casadi.colregs.verdict import RuleResult

_PARALLEL = 1e-12


def channel_sides(xy, psi, segments):
    """Distances to the nearest bank to port and to starboard, across each sample's heading.

    Parameters
    ----------
    xy : array (K, 2)
        Ship positions (L).
    psi : array (K,)
        Headings (rad, from x towards y; starboard is ψ + 90°).
    segments : sequence of ((ax, ay), (bx, by))
        Walls and land edges (L).

    Returns
    -------
    d_port, d_stbd : array (K,)
        Distance (L) along the perpendicular to the heading to the nearest segment on each side (``inf`` for none).
    """
    xy, psi = np.asarray(xy, float).reshape(-1, 2), np.asarray(psi, float).ravel()
    k = xy.shape[0]
    if not len(segments):
        return np.full(k, np.inf), np.full(k, np.inf)
    seg = np.asarray(segments, float).reshape(-1, 4)
    a, e = seg[None, :, 0:2], seg[None, :, 2:4] - seg[None, :, 0:2]
    n = np.column_stack([-np.sin(psi), np.cos(psi)])[:, None, :]  # starboard unit normal
    ap = a - xy[:, None, :]
    denom = n[..., 0] * e[..., 1] - n[..., 1] * e[..., 0]  # n × e
    ok = np.abs(denom) > _PARALLEL
    safe = np.where(ok, denom, 1.0)
    s = (ap[..., 0] * e[..., 1] - ap[..., 1] * e[..., 0]) / safe  # p + s n = a + u e: s = ((a − p) × e) / (n × e)
    u = (ap[..., 0] * n[..., 1] - ap[..., 1] * n[..., 0]) / safe  # u = ((a − p) × n) / (n × e)
    hit = ok & (u >= 0.0) & (u <= 1.0)
    d_stbd = np.where(hit & (s > 0), s, np.inf).min(axis=1)
    d_port = np.where(hit & (s < 0), -s, np.inf).min(axis=1)
    return d_port, d_stbd


def rule9(t, xy, psi, active, segments, *, profile=None):
    """Rule 9(a) verdict of one ship: the share of her time in a narrow channel on its starboard side.

    Parameters
    ----------
    t : array (K,)
        Sample times (L/U); each sample stands for the time to the next.
    xy : array (K, 2)
        Positions (L).
    psi : array (K,)
        Headings (rad).
    active : array (K,) of bool
        Whether the ship sails at each sample.
    segments : sequence of ((ax, ay), (bx, by))
        Walls and land edges of the scenario (L).
    profile : str or ScoringProfile, optional
        The scoring profile (:func:`~mmg_casadi.colregs.profiles.scoring_profile`; default ``published``): its
        ``rule9_width`` is the widest channel that counts as narrow (L), its ``rule9_kept_share`` the least
        starboard share for the rule to be kept.

    Returns
    -------
    RuleResult or None
        ``None`` when the ship is never in a narrow channel while she sails; else the verdict (share ≥
        ``kept_share``), the score (the share) and the terms ``channel_time`` (L/U), ``starboard_time`` (L/U),
        ``share``, ``mean_offset`` (L, time-weighted mean offset from the centre line, > 0 to starboard) and
        ``min_width`` (L, the narrowest cross-section met).
    """
    p = scoring_profile(profile)
    width, kept_share = p.rule9_width, p.rule9_kept_share
    t = np.asarray(t, float).ravel()
    if t.size < 2 or not len(segments):
        return None
    d_port, d_stbd = channel_sides(xy, psi, segments)
    w = d_port + d_stbd  # channel width across the track (eq. channel_width)
    inside = np.asarray(active, bool).ravel() & np.isfinite(w) & (w <= width)
    dt = np.append(np.diff(t), 0.0)
    channel_time = float(np.sum(dt[inside]))
    if channel_time <= 0.0:
        return None
    offset = np.zeros(w.shape)
    offset[inside] = 0.5 * (d_port[inside] - d_stbd[inside])  # lateral offset from the centre line (eq. channel_offset)
    starboard_time = float(np.sum(dt[inside & (offset > 0)]))
    share = starboard_time / channel_time
    return RuleResult(share >= kept_share, share, {
        "channel_time": channel_time, "starboard_time": starboard_time, "share": share,
        "mean_offset": float(np.sum(dt * offset) / channel_time), "min_width": float(np.min(w[inside]))})
