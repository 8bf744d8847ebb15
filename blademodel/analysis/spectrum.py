"""Amplitude spectrum over a whole number of excitation periods."""

from __future__ import annotations

import numpy as np


def amplitude_spectrum(x, samples_per_period: int) -> tuple[np.ndarray, np.ndarray]:
    """One-sided amplitude spectrum of a signal sampled on whole excitation periods.

    Parameters
    ----------
    x : array_like
        Uniform samples covering ``K`` whole periods: ``K * samples_per_period``
        values, or one more (a closing sample equal in time to the first of the
        next period, which is dropped).
    samples_per_period : int

    Returns
    -------
    ratio : ndarray
        Frequencies as ``f / f_e`` (``f_e`` the excitation frequency): ``k / K``.
    amplitude : ndarray
        Amplitude of each harmonic, in the units of ``x`` (the mean at ``k = 0``).
        A component ``A cos(2 pi f t + phi)`` with ``f / f_e = k / K`` shows ``A``.
    """
    x = np.asarray(x, dtype=float)
    S = int(samples_per_period)
    if len(x) % S == 1:
        x = x[:-1]
    if len(x) % S or len(x) == 0:
        raise ValueError(f"{len(x)} samples are not a whole number of periods of {S} samples")
    K = len(x) // S
    X = np.fft.rfft(x) / len(x)
    amp = 2 * np.abs(X)
    amp[0] /= 2
    if len(x) % 2 == 0:
        amp[-1] /= 2
    return np.arange(len(X)) / K, amp
