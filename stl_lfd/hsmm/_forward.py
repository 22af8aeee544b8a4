"""Forward-backward recursions of the skill model, as free functions on plain arrays.

- `hmm_posteriors`: scaled HMM forward-backward over a batch of padded sequences (EM's E-step).
- `state_occupancy`: the HSMM explicit-duration forward variable without observations, in its
  occupancy form a(i, d) = P(state i with d steps left), which gives the state sequence used
  for retrieval.
"""

from __future__ import annotations

import numpy as np


def hmm_posteriors(startprob: np.ndarray, transmat: np.ndarray, frame_likelihood: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scaled forward-backward for a batch of sequences padded to a common length.

    Args:
        startprob: `K` initial distribution.
        transmat: `K x K` transition matrix (rows sum to 1).
        frame_likelihood: `B x T x K` observation likelihoods (any positive scale per frame).
        lengths: `B` true lengths; frames at or beyond a sequence's length are ignored.

    Returns:
        gamma: `B x T x K` state posteriors (zero on padding),
        xi_sum: `K x K` expected transition counts summed over sequences and time,
        log_likelihood: `B` log-likelihoods (up to the frame scales).
    """
    batch, steps, states = frame_likelihood.shape
    valid = np.arange(steps)[None, :] < lengths[:, None]  # B x T
    alpha = np.zeros((batch, steps, states))
    scale = np.ones((batch, steps))
    current = startprob[None, :] * frame_likelihood[:, 0]
    for t in range(steps):
        if t > 0:
            current = (alpha[:, t - 1] @ transmat) * frame_likelihood[:, t]
        total = current.sum(axis=1)
        total = np.where(valid[:, t] & (total > 0), total, 1.0)
        alpha[:, t] = current / total[:, None]
        scale[:, t] = total
    beta = np.ones((batch, steps, states))
    weighted = np.empty((batch, steps, states))  # b_{t}(j) beta_t(j) / c_t
    for t in range(steps - 1, 0, -1):
        weighted[:, t] = frame_likelihood[:, t] * beta[:, t] / scale[:, t, None]
        beta[:, t - 1] = np.where(valid[:, t, None], weighted[:, t] @ transmat.T, 1.0)
    # xi_t(i, j) = alpha_t(i) A_ij b_{t+1}(j) beta_{t+1}(j) / c_{t+1}, summed over valid t.
    transitions = valid[:, 1:, None]
    xi_sum = transmat * np.einsum("bti,btj->ij", alpha[:, :-1] * transitions, weighted[:, 1:])
    gamma = alpha * beta * valid[..., None]
    gamma /= np.maximum(gamma.sum(axis=2, keepdims=True), 1e-300)
    log_likelihood = np.where(valid, np.log(scale), 0.0).sum(axis=1)
    return gamma, xi_sum, log_likelihood


def duration_pmf(means: np.ndarray, stds: np.ndarray, max_steps: int) -> np.ndarray:
    """Discretised Gaussian duration probabilities over 1..max_steps steps.

    Args:
        means, stds: `K` duration means and standard deviations, in steps.
        max_steps: longest duration considered.

    Returns:
        `K x max_steps` array; entry (i, d-1) is P(duration of state i = d steps), each row
        normalised to sum to 1.
    """
    edges = np.arange(max_steps + 1) + 0.5  # bin d covers (d - 0.5, d + 0.5]
    from scipy.special import ndtr  # the standard normal CDF, without loading scipy.stats

    cdf = ndtr((edges[None, :] - means[:, None]) / stds[:, None])
    pmf = np.diff(cdf, axis=1)
    pmf[:, 0] += cdf[:, 0]  # durations below one step count as one step
    return pmf / np.maximum(pmf.sum(axis=1, keepdims=True), 1e-300)


def state_occupancy(startprob: np.ndarray, transmat: np.ndarray, pmf: np.ndarray, steps: int) -> np.ndarray:
    """P(state i at step t) of the HSMM without observations.

    Occupancy form of the forward variable:
        a_1(i, d) = pi_i p_i(d);  S_t(i) = sum_j A_ji a_t(j, 1);
        a_{t+1}(i, d) = S_t(i) p_i(d) + a_t(i, d + 1);  h_t(i) = sum_d a_t(i, d).
    Unrolled, a_t(i, 1) = pi_i p_i(t) + sum_{s<t} S_s(i) p_i(t - s) and h_t(i) is the same
    convolution with the survival function P_i(>= n); the loop only computes a_t(., 1) and S_t,
    and h follows by one convolution afterwards.

    States whose row of `transmat` is all zero (no successor) are absorbing: when their
    duration ends they start again, so no probability leaks at the end of the skill.

    Args:
        startprob: `K`.
        transmat: `K x K`, rows summing to 1 or 0.
        pmf: `K x D` duration probabilities over 1..D steps (rows sum to 1).
        steps: number of steps T.

    Returns:
        `T x K` occupancy probabilities, each row summing to 1.
    """
    states, max_steps = pmf.shape
    renewal = transmat.copy()
    final = renewal.sum(axis=1) <= 0
    renewal[final, final] = 1.0
    survival = np.cumsum(pmf[:, ::-1], axis=1)[:, ::-1]  # K x D: P(duration >= n), n = 1..D
    reversed_pmf = pmf[:, ::-1]  # column D-1-k holds p(k+1)
    entries = np.zeros((steps, states))  # S_t: probability of entering i at t+1
    for t in range(steps):
        # 0-based t: a_t(i, 1) = pi_i p_i(t + 1) + sum_{s < t} S_s(i) p_i(t - s)
        first = startprob * pmf[:, t] if t < max_steps else np.zeros(states)
        begin = max(0, t - max_steps)
        if t > 0:
            history = entries[begin:t]  # (t - begin) x K, S_s for s in [begin, t)
            kernel = reversed_pmf[:, max_steps - (t - begin) :]  # K x (t - begin): p_i(t - s)
            first = first + np.einsum("sk,ks->k", history, kernel)
        entries[t] = first @ renewal
    return _occupancy_from_entries(startprob, entries, survival, steps)


def _occupancy_from_entries(startprob: np.ndarray, entries: np.ndarray, survival: np.ndarray, steps: int) -> np.ndarray:
    """h_t(i) = pi_i P_i(>= t + 1) + sum_{s < t} S_s(i) P_i(>= t - s), by FFT convolution."""
    states, max_steps = survival.shape
    kernel = np.zeros((states, steps))
    width = min(max_steps, steps)
    kernel[:, :width] = survival[:, :width]  # kernel[n-1] = P(>= n)
    occupancy = startprob[:, None] * kernel  # pi_i P_i(>= t + 1)
    shifted = np.zeros((states, steps))
    shifted[:, 1:] = entries[:-1].T  # S_{t-1} enters at t
    from scipy.signal import fftconvolve

    occupancy += fftconvolve(shifted, kernel, axes=1)[:, :steps]
    occupancy = np.clip(occupancy.T, 0.0, None)
    return occupancy / np.maximum(occupancy.sum(axis=1, keepdims=True), 1e-300)
