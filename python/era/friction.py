"""Actuator Coulomb friction from free-decay records (thesis §III.3).

A spring-mass actuator released from rest decays with a velocity amplitude that drops
by the same amount each cycle under Coulomb friction, and by the same ratio under
viscous damping. ``estimate`` fits both and gives the friction force of Eq. 3.12,
``F_C = Δv · k / (8 π f_n)`` with ``Δv`` the drop per cycle, as
``era friction estimate`` does.
"""

from typing import Any, Dict

from ._era import friction_estimate as _friction_estimate

__all__ = ["estimate"]


def estimate(time_s: Any, velocity: Any, stiffness: float) -> Dict[str, Any]:
    """Friction of one free-decay velocity record.

    Parameters
    ----------
    time_s : array_like, shape (samples,)
        Sample times, s, strictly increasing.
    velocity : array_like, shape (samples,)
        Velocity of the mass (any length unit per second).
    stiffness : float
        Net spring stiffness k, force per length (thesis: 1.0 lbf/in).

    Returns
    -------
    dict
        The CLI's JSON fields (``era friction estimate --json``, one record):
        ``coulomb_force``, ``natural_frequency_hz``, ``natural_frequency_hz_from_peaks``,
        ``cycles``, ``velocity_drop_per_cycle``, ``viscous_damping_ratio``,
        ``better_model`` ("coulomb" or "viscous"), ``coulomb_residual``,
        ``viscous_residual``, ``half_cycles_fitted``, ``fit_start_s``, ``fit_end_s``,
        ``noise_rms``, ``signal`` and ``stiffness``.

    Raises
    ------
    ValueError
        A non-positive stiffness, non-finite samples, times not increasing, or too few
        cycles to fit (the CLI's messages).
    """
    return _friction_estimate(time_s, velocity, stiffness)
