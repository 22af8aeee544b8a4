"""Learning an HSMM's parameters from demonstrations: k-bins starts, Baum-Welch on the
equivalent left-right HMM, then a Gaussian duration per state and the Gaussian of the end
points (`HSMM.fit` runs them in this order). Functions of the model they set."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.hsmm._forward import hmm_posteriors

# The model these functions learn the parameters of: an `HSMM` (`stl_lfd.hsmm.model`, which
# imports this module, so it is named here rather than imported).
HSMM = Any

logger = logging.getLogger(__name__)


@dataclass
class ConvergenceMonitor:
    """Log-likelihood history of EM; `converged` once an iteration gains less than `tol`."""

    tol: float
    n_iter: int
    history: list[float] = field(default_factory=list)

    def report(self, log_likelihood: float) -> None:
        logger.debug("EM iteration %d: log-likelihood %.6f", len(self.history) + 1, log_likelihood)
        self.history.append(log_likelihood)

    @property
    def converged(self) -> bool:
        if len(self.history) >= self.n_iter:
            return True
        return len(self.history) >= 2 and self.history[-1] - self.history[-2] < self.tol


def baum_welch(model: HSMM, sequences: list[np.ndarray], lengths: np.ndarray) -> np.ndarray:
    """Baum-Welch from the current means and covariances: sets the parameters and
    `monitor_`, returns the last posteriors (`B x T x K`)."""
    padded = pad_sequences(sequences)
    model.monitor_ = ConvergenceMonitor(model.tol, model.n_iter)
    transmat = left_right_start(model, lengths)
    valid = np.arange(padded.shape[1])[None, :] < lengths[:, None]
    while True:
        likelihood, log_scale = frame_likelihood(model, padded)
        gamma, xi_sum, log_likelihood = hmm_posteriors(model.startprob_, transmat, likelihood, lengths)
        model.monitor_.report(float(log_likelihood.sum() + log_scale[valid].sum()))
        transmat = m_step(model, padded, gamma, xi_sum, lengths)
        if model.monitor_.converged:
            break
    set_transitions(model, transmat)
    return gamma


def kbins_start(model: HSMM, sequences: list[np.ndarray], rng: np.random.Generator | None = None) -> None:
    """k-bins: cut every demonstration into K equal time bins (with `rng`, K bins of random
    lengths); state k starts as bin k."""
    K, D = model.n_states, sequences[0].shape[1]
    if rng is None:
        bins = [np.array_split(sequence, K) for sequence in sequences]
    else:
        bins = [np.split(sequence, np.sort(rng.choice(np.arange(1, len(sequence)), K - 1, replace=False))) for sequence in sequences]
    pooled = [np.concatenate([b[k] for b in bins]) for k in range(K)]
    coordinates = model.coordinates()
    if not coordinates.rotations:
        model.means_ = np.array([samples.mean(axis=0) for samples in pooled])
        covars = [np.atleast_2d(np.cov(samples.T, bias=True)) if len(samples) > 1 else np.zeros((D, D)) for samples in pooled]
    else:
        model.means_ = np.array([coordinates.mean(samples, np.ones(len(samples))) for samples in pooled])
        deviations = [coordinates.deviations(samples, mean) for samples, mean in zip(pooled, model.means_)]
        covars = [deviation.T @ deviation / len(deviation) for deviation in deviations]
    model.covars_ = model._constrained(np.array(covars)) + model.reg_covar * np.eye(D)
    model.startprob_ = np.eye(K)[0]


def left_right_start(model: HSMM, lengths: np.ndarray) -> np.ndarray:
    K = model.n_states
    leave = min(0.5, K / float(np.mean(lengths)))
    transmat = np.eye(K) * (1 - leave) + np.eye(K, k=1) * leave
    transmat[-1, -1] = 1.0
    return transmat


def frame_likelihood(model: HSMM, padded: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`B x T x K` Gaussian likelihoods divided by their largest value per frame, and the
    `B x T` logs of those divisors (which the log-likelihood adds back)."""
    coordinates = model.coordinates()
    if not coordinates.rotations:
        log_likelihood = np.stack([gaussian_log_density(padded, model.means_[k], model.covars_[k]) for k in range(model.n_states)], axis=-1)
    else:
        deviations = [coordinates.deviations(padded, model.means_[k]) for k in range(model.n_states)]
        log_likelihood = np.stack([gaussian_log_density(deviations[k], 0.0, model.covars_[k]) for k in range(model.n_states)], axis=-1)
    log_scale = log_likelihood.max(axis=-1)
    # Floor: a frame that no reachable state explains must not zero the forward pass.
    return np.exp(np.maximum(log_likelihood - log_scale[..., None], -300.0)), log_scale


def m_step(model: HSMM, padded: np.ndarray, gamma: np.ndarray, xi_sum: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    D = padded.shape[-1]
    weights = gamma.sum(axis=(0, 1))  # K
    safe = np.maximum(weights, 1e-12)
    coordinates = model.coordinates()
    if not coordinates.rotations:
        model.means_ = np.einsum("btk,btd->kd", gamma, padded) / safe[:, None]
        centred = padded[:, :, None, :] - model.means_[None, None]  # B x T x K x D
    else:
        points, weights = padded.reshape(-1, D), gamma.reshape(-1, model.n_states)
        model.means_ = np.array([coordinates.mean(points, weights[:, k], model.means_[k]) for k in range(model.n_states)])
        centred = np.stack([coordinates.deviations(padded, model.means_[k]) for k in range(model.n_states)], axis=2)
    model.covars_ = model._constrained(np.einsum("btk,btkd,btke->kde", gamma, centred, centred) / safe[:, None, None])
    model.covars_ += model.reg_covar * np.eye(D)
    transmat = xi_sum / np.maximum(xi_sum.sum(axis=1, keepdims=True), 1e-300)
    starts = gamma[:, 0].sum(axis=0)
    model.startprob_ = starts / starts.sum()
    return transmat


def set_transitions(model: HSMM, hmm_transmat: np.ndarray) -> None:
    transmat = hmm_transmat * (1 - np.eye(model.n_states))
    totals = transmat.sum(axis=1, keepdims=True)
    model.transmat_ = np.divide(transmat, totals, out=np.zeros_like(transmat), where=totals > 1e-8)


def fit_durations(model: HSMM, gamma: np.ndarray, lengths: np.ndarray) -> None:
    """Duration mean and std (s) from the runs of the most likely state in each demo."""
    runs: list[list[int]] = [[] for _ in range(model.n_states)]
    for b, length in enumerate(lengths):
        labels = gamma[b, :length].argmax(axis=1)
        boundaries = np.flatnonzero(np.diff(labels)) + 1
        for segment in np.split(labels, boundaries):
            runs[segment[0]].append(len(segment))
    all_runs = [run for state_runs in runs for run in state_runs]
    means, stds = np.empty(model.n_states), np.empty(model.n_states)
    for k, state_runs in enumerate(runs):
        sample = np.array(state_runs or [np.mean(all_runs)], dtype=float)
        means[k] = sample.mean()
        stds[k] = np.sqrt(max(sample.var(), 1.0))  # variance floor of one step squared
        if not state_runs:
            logger.warning("state %d is never the most likely one in the demonstrations", k)
    model.duration_means_ = means * model.sample_period_
    model.duration_stds_ = stds * model.sample_period_


def fit_end(model: HSMM, ends: np.ndarray) -> None:
    """The Gaussian of the demonstrations' end points (`B x D`), attached to the final
    state of the nominal path as an offset from its mean, so that moving that state's
    mean moves the end with it."""
    model.end_state_ = model.nominal_path()[-1]
    coordinates = model.coordinates()
    if not coordinates.rotations:
        model.end_offsets_ = ends.mean(axis=0) - model.means_[model.end_state_]
        spread = np.atleast_2d(np.cov(ends.T, bias=True)) if len(ends) > 1 else np.zeros((ends.shape[1],) * 2)
    else:
        end = coordinates.mean(ends, np.ones(len(ends)), ends[0])
        model.end_offsets_ = coordinates.deviations(end, model.means_[model.end_state_])
        deviations = coordinates.deviations(ends, end)
        spread = deviations.T @ deviations / len(ends)
    model.end_covars_ = model._constrained(spread) + model.reg_covar * np.eye(ends.shape[1])


def gaussian_log_density(points: np.ndarray, mean: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """Log density of the normal distribution (`D` mean, `D x D` covariance, possibly singular)
    at `... x D` points: an array of shape `...`, -inf off the support of a singular one.

    The arithmetic of scipy's `multivariate_normal(mean, covariance, allow_singular=True)
    .logpdf`, step for step (a test checks that the values are bit-identical), without importing
    `scipy.stats`, which costs every command that learns about 0.8 s more than `scipy.linalg`.
    """
    from scipy.linalg import eigh

    eigenvalues, eigenvectors = eigh(covariance, lower=True, check_finite=True)
    negligible = 1e6 * np.finfo(float).eps * np.max(np.abs(eigenvalues))
    if np.min(eigenvalues) < -negligible:
        raise ModelError("a state's covariance is not positive semidefinite")
    kept = eigenvalues[eigenvalues > negligible]
    inverse = np.array([0 if abs(value) <= negligible else 1 / value for value in eigenvalues], dtype=float)
    whitening = np.multiply(eigenvectors, np.sqrt(inverse))
    rank, log_determinant = np.int64(len(kept)), np.sum(np.log(kept))
    deviation = np.asarray(points, dtype=float) - mean
    distance = np.sum(np.square(deviation @ whitening), axis=-1)
    density = -0.5 * (rank * np.log(2 * np.pi) + log_determinant + distance)
    if rank < len(eigenvalues):
        residual = np.linalg.norm(deviation @ eigenvectors[:, eigenvalues <= negligible], axis=-1)
        density[~(residual < 1e3 * negligible)] = -np.inf
    return density


def pad_sequences(sequences: list[np.ndarray]) -> np.ndarray:
    """`B x T_max x D` array, sequences padded with their last sample."""
    longest = max(len(sequence) for sequence in sequences)
    return np.stack([np.concatenate([s, np.repeat(s[-1:], longest - len(s), axis=0)]) for s in sequences])
