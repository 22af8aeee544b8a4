"""Hidden semi-Markov model with Gaussian emissions and Gaussian state durations.

Follows hmmlearn's conventions: `__init__` stores hyperparameters only, `fit(X, lengths)`
learns the attributes ending in `_` and returns `self`, several sequences are passed
concatenated with their `lengths`, and `_check()` validates the parameters before use.
"""

from __future__ import annotations

import logging

import numpy as np

import stl_lfd.rotations as rotations
from stl_lfd.errors import ModelError
from stl_lfd.hsmm import em
from stl_lfd.hsmm._forward import duration_pmf, hmm_posteriors, state_occupancy
from stl_lfd.hsmm.orientation import Coordinates, to_model_columns
from stl_lfd.hsmm.spread import MinimumSpread, widened

logger = logging.getLogger(__name__)


class HSMM:
    """Skill model: K Gaussian states, a transition matrix without self-transitions, and a
    Gaussian duration per state.

    Hyperparameters:
        n_states: K.
        n_iter, tol: EM iteration limit and log-likelihood gain that stops it.
        reg_covar: added to the diagonal of every covariance (units of the signals squared).
        min_spread: after learning, every state (and the end point) is widened to at least this
            standard deviation in every direction, and every duration to at least this
            fraction of its mean (`stl_lfd.hsmm.spread`; for one demonstration); None: no floor.

    Learned attributes (plain arrays, free to modify before `state_sequence` or retrieval):
        means_: `K x D` state means.
        covars_: `K x D x D` state covariances.
        duration_means_, duration_stds_: `K` duration mean and standard deviation, seconds.
        transmat_: `K x K` transition probabilities, zero diagonal; a row of zeros marks a final
            state. Rows are normalised where they are used, so any non-negative values work.
        startprob_: `K` initial distribution.
        sample_period_: seconds between samples of the data the model was fitted on.
        signal_names_: the D signal names (the model's columns: with orientation, `rx, ry, rz`
            in place of the demonstrations' `qx, qy, qz, qw`).
        orientation_reference_: for a skill with orientation, the quaternion its rotation
            vectors are relative to (see `stl_lfd.hsmm.orientation`); None for positions only.
        end_state_, end_offsets_, end_covars_: where the demonstrations end: the final state
            of the nominal path, the `D` offset of the mean end point from that state's mean,
            and the `D x D` covariance of the end points. Retrieval tracks this end for the
            second half of the final state, so that the skill finishes where the
            demonstrations do rather than at the final state's mean (the average of a segment
            that may still be moving). None in models from older files.
    """

    def __init__(
        self, n_states: int = 6, n_iter: int = 50, tol: float = 1e-2, reg_covar: float = 1e-6, n_init: int = 1, min_spread: MinimumSpread | None = None
    ) -> None:
        self.n_states = n_states
        self.n_iter = n_iter
        self.tol = tol
        self.reg_covar = reg_covar
        self.n_init = n_init
        self.min_spread = min_spread

    # --- learning -------------------------------------------------------------------------

    def fit(self, X: np.ndarray, lengths: np.ndarray, sample_period: float, signal_names: list[str] | None = None) -> "HSMM":
        """Learn the model from demonstrations.

        Args:
            X: `N x D` samples of all demonstrations, concatenated.
            lengths: samples per demonstration (sums to N).
            sample_period: seconds between samples (all demonstrations share it).
            signal_names: names of the D columns; `qx, qy, qz, qw` (a unit quaternion per
                sample, continuous) make it a skill with orientation.

        Recipe: k-bins initialisation, left-right HMM Baum-Welch with covariance
        regularisation, self-transitions removed, then a Gaussian duration per state from the
        segment lengths of the most likely state at each sample. With `n_init` above 1, EM
        also starts from `n_init - 1` other segmentations (each demonstration cut into K
        random-length bins, seeded) and the start of highest likelihood is kept.
        """
        X = np.asarray(X, dtype=float)
        lengths = np.asarray(lengths, dtype=int)
        self._check_data(X, lengths)
        names = list(signal_names) if signal_names is not None else [f"s{i}" for i in range(X.shape[1])]
        X, self.signal_names_, reference = to_model_columns(X, names)
        if reference is not None or not self.coordinates().rotations:  # a TP-HSMM sets its frames' references itself
            self.orientation_reference_ = reference
        self.sample_period_ = float(sample_period)
        sequences = np.split(X, np.cumsum(lengths)[:-1])
        best = None
        for start in range(max(self.n_init, 1)):
            em.kbins_start(self, sequences, None if start == 0 else np.random.default_rng(start))
            try:
                gamma = em.baum_welch(self, sequences, lengths)
            except (ValueError, np.linalg.LinAlgError, ModelError):
                if start == 0:
                    raise
                continue  # a random start that degenerated (a state left without samples)
            if best is None or self.monitor_.history[-1] > best[0]:  # NaN never wins
                best = (self.monitor_.history[-1], self._learned(), gamma)
        _, learned, gamma = best
        for name, value in learned.items():
            setattr(self, name, value)
        em.fit_durations(self, gamma, lengths)
        em.fit_end(self, np.array([sequence[-1] for sequence in sequences]))
        if self.min_spread is not None:
            self._widen(self.min_spread)
        self._check()
        return self

    def _widen(self, spread: MinimumSpread) -> None:
        stds = spread.column_stds(self.coordinates(), self.means_.shape[1])
        self.covars_ = widened(self.covars_, stds)
        self.end_covars_ = widened(self.end_covars_, stds)
        self.duration_stds_ = np.maximum(self.duration_stds_, spread.duration * self.duration_means_)

    def _learned(self) -> dict:
        """The EM's results so far (to keep the best of several starts)."""
        return {name: getattr(self, name) for name in ("means_", "covars_", "startprob_", "transmat_", "monitor_")}

    def predict(self, X: np.ndarray, lengths: np.ndarray | None = None) -> np.ndarray:
        """Most likely state at each sample (HMM posteriors with self-transitions restored
        from the duration means), `N` integers."""
        self._check()
        X = np.asarray(X, dtype=float)
        lengths = np.array([len(X)]) if lengths is None else np.asarray(lengths, dtype=int)
        padded = em.pad_sequences(np.split(X, np.cumsum(lengths)[:-1]))
        gamma, _, _ = hmm_posteriors(self.startprob_, self._hmm_transmat(), em.frame_likelihood(self, padded)[0], lengths)
        return np.concatenate([gamma[b, : lengths[b]].argmax(axis=1) for b in range(len(lengths))])

    def score(self, X: np.ndarray, lengths: np.ndarray | None = None) -> float:
        """Log-likelihood of the samples `X` (`N x D`, in the model's columns) under the model
        (its HMM equivalent, as `predict`), summed over the sequences of `lengths`."""
        self._check()
        X = np.asarray(X, dtype=float)
        lengths = np.array([len(X)]) if lengths is None else np.asarray(lengths, dtype=int)
        padded = em.pad_sequences(np.split(X, np.cumsum(lengths)[:-1]))
        likelihood, log_scale = em.frame_likelihood(self, padded)
        _, _, log_likelihood = hmm_posteriors(self.startprob_, self._hmm_transmat(), likelihood, lengths)
        valid = np.arange(padded.shape[1])[None, :] < lengths[:, None]
        return float(log_likelihood.sum() + log_scale[valid].sum())

    # --- generation ------------------------------------------------------------------------

    def state_sequence(self, steps: int, dt: float | None = None) -> np.ndarray:
        """The state followed at each of `steps` steps of `dt` seconds (default the model's
        sample period): the `nominal_path`, each state held for its duration mean, the last
        one until the end.

        This is the paper's rule and always a feasible path of the model: every switch is a
        transition of positive probability (the argmax of the marginal occupancy is not: it
        can skip a state and take a transition of probability 0). Switches fall at the rounded
        cumulative duration means (each state keeps one step at least), so the sequence reaches
        its last state after `expected_duration()` minus that state's duration.
        """
        self._check()
        dt = self.sample_period_ if dt is None else dt
        path = self._nominal_path()
        sequence = np.full(steps, path[-1], dtype=int)
        start = 0
        for state, end in zip(path[:-1], np.cumsum(self.duration_means_[path[:-1]]) / dt):
            stop = max(int(round(end)), start + 1)  # every state of the path lasts a step at least
            sequence[start:stop] = state
            start = stop
        return sequence

    def nominal_path(self) -> list[int]:
        """States in the order the skill visits them: from the most likely first state, the
        most likely successor of each, until a state without successors or one already visited.
        Ties go to the lower state number."""
        self._check()
        return self._nominal_path()

    def _nominal_path(self) -> list[int]:
        """`nominal_path` of a checked model."""
        transmat = self.normalized_transmat()
        path = [int(np.argmax(self.startprob_))]
        while transmat[path[-1]].sum() > 0:
            successor = int(np.argmax(transmat[path[-1]]))
            if successor in path:
                break
            path.append(successor)
        return path

    def state_probabilities(self, steps: int, dt: float | None = None) -> np.ndarray:
        """`steps x K` probabilities of being in each state (rows sum to 1)."""
        self._check()
        dt = self.sample_period_ if dt is None else dt
        means, stds = self.duration_means_ / dt, np.maximum(self.duration_stds_ / dt, 1.0)
        max_steps = int(np.ceil(np.max(means + 4 * stds))) + 1
        pmf = duration_pmf(means, stds, max_steps)
        return state_occupancy(self.startprob_, self.normalized_transmat(), pmf, steps)

    def expected_duration(self) -> float:
        """Seconds the nominal state sequence takes: the duration means along `nominal_path`."""
        return float(np.sum(self.duration_means_[self.nominal_path()]))

    def sample(self, duration: float, random_state: int | np.random.Generator | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Draw one sequence of `duration` seconds at the model's sample period.

        Returns:
            X: `T x D` samples, states: `T` state indices.
        """
        self._check()
        rng = np.random.default_rng(random_state)
        steps = int(round(duration / self.sample_period_))
        transmat = self.normalized_transmat()
        states = np.empty(steps, dtype=int)
        state, t = rng.choice(self.n_states, p=self.startprob_), 0
        while t < steps:
            length = max(1, int(round(rng.normal(self.duration_means_[state], self.duration_stds_[state]) / self.sample_period_)))
            states[t : t + length] = state
            t += length
            if transmat[state].sum() > 0:
                state = rng.choice(self.n_states, p=transmat[state])
        coordinates = self.coordinates()
        if not coordinates.rotations:
            X = np.array([rng.multivariate_normal(self.means_[k], self.covars_[k]) for k in states])
        else:
            X = np.array([coordinates.shifted(self.means_[k], rng.multivariate_normal(np.zeros(self.n_features), self.covars_[k])) for k in states])
        return X, states

    # --- parameters ------------------------------------------------------------------------

    def normalized_transmat(self) -> np.ndarray:
        """`transmat_` with negative entries clipped and non-zero rows scaled to sum to 1."""
        transmat = np.clip(np.asarray(self.transmat_, dtype=float), 0.0, None)
        totals = transmat.sum(axis=1, keepdims=True)
        return np.divide(transmat, totals, out=np.zeros_like(transmat), where=totals > 0)

    def _check(self) -> None:
        for name in ("means_", "covars_", "duration_means_", "duration_stds_", "transmat_", "startprob_", "sample_period_", "signal_names_"):
            if not hasattr(self, name):
                raise ModelError(f"the model has no {name}: fit it or load a model file first")
        K, D = np.shape(self.means_)
        expected = {
            "covars_": (K, D, D),
            "duration_means_": (K,),
            "duration_stds_": (K,),
            "transmat_": (K, K),
            "startprob_": (K,),
        }
        for name, shape in expected.items():
            if np.shape(getattr(self, name)) != shape:
                raise ModelError(f"{name} must have shape {shape} (got {np.shape(getattr(self, name))})")
        arrays = [self.means_, self.covars_, self.duration_means_, self.duration_stds_, self.transmat_, self.startprob_]
        if not all(np.all(np.isfinite(a)) for a in arrays):
            raise ModelError("model parameters contain NaN or infinity")
        if np.any(np.asarray(self.duration_means_) <= 0) or np.any(np.asarray(self.duration_stds_) <= 0):
            raise ModelError(f"duration means and stds must be positive (got means {np.round(self.duration_means_, 3)})")
        if len(self.feature_names) != D:
            raise ModelError(f"the {D} columns of means_ do not match the signals {', '.join(self.feature_names)}")
        end = self.end_target()
        if end is not None and not (0 <= end[0] < K and np.shape(self.end_offsets_) == (D,) and np.shape(end[2]) == (D, D)):
            raise ModelError(f"end_state_, end_offsets_ and end_covars_ must be a state, ({D},) and ({D}, {D})")
        if end is not None and not (np.all(np.isfinite(end[1])) and np.all(np.isfinite(end[2]))):
            raise ModelError("the end point contains NaN or infinity")
        blocks = len(self.coordinates().rotations)
        references = np.atleast_2d(self.orientation) if self.orientation is not None else np.empty((0, 4))
        if blocks and not (references.shape == (blocks, 4) and np.allclose(np.linalg.norm(references, axis=-1), 1.0)):
            raise ModelError(f"a model with orientation (rx, ry, rz) needs orientation_reference_: {blocks} unit quaternion(s), one per frame")
        if not np.isclose(np.sum(self.startprob_), 1.0):
            raise ModelError(f"startprob_ must sum to 1 (got {np.sum(self.startprob_):.6g})")

    @property
    def orientation(self) -> np.ndarray | None:
        """The quaternion the model's rotation vectors are relative to (for a TP-HSMM, one per
        frame); None for positions only (and for models from files written before skills had
        orientation)."""
        return getattr(self, "orientation_reference_", None)

    def orientations(self, points: np.ndarray) -> np.ndarray | None:
        """`... x 4` quaternions of `... x D` points in the model's columns (None without orientation)."""
        rotation = self.coordinates().rotation
        if rotation is None:
            return None
        return rotations.exp_map(self.orientation, np.asarray(points)[..., rotation])

    @property
    def n_features(self) -> int:
        return int(np.shape(self.means_)[1])

    @property
    def feature_names(self) -> list[str]:
        """The name of each column of `means_`."""
        return list(self.signal_names_)

    def coordinate(self, name: str, frame: str | None = None) -> int:
        """The column of `means_` holding signal `name` (in `frame`, for a model with frames);
        ModelError when there is none."""
        offset = self._frame_offset(frame)
        if name not in self.signal_names_:
            raise ModelError(f"the model has no signal {name} ({', '.join(self.signal_names_)})")
        return offset + self.signal_names_.index(name)

    def _frame_offset(self, frame: str | None) -> int:
        """Where the columns of `frame` start in `means_` (only one frame here: no name)."""
        if frame is not None:
            raise ModelError(f"the model has no frames (it was learned without frame sidecars), so there is no frame {frame}")
        return 0

    # --- EM internals ----------------------------------------------------------------------

    def _check_data(self, X: np.ndarray, lengths: np.ndarray) -> None:
        if X.ndim != 2 or lengths.sum() != len(X):
            raise ModelError(f"lengths {lengths.tolist()} do not sum to {len(X)} samples")
        shortest = int(lengths.min())
        if shortest < self.n_states:
            raise ModelError(
                f"K = {self.n_states} states need demonstrations of at least {self.n_states} samples (the shortest has {shortest}); use a smaller K"
            )

    def coordinates(self) -> Coordinates:
        """Where the model's columns hold an orientation (see `stl_lfd.hsmm.orientation`)."""
        return Coordinates.of(self.feature_names)

    def _constrained(self, covars: np.ndarray) -> np.ndarray:
        """The covariances EM may use (all of them here; block-diagonal in `TPHSMM`)."""
        return covars

    def end_target(self) -> tuple[int, np.ndarray, np.ndarray] | None:
        """(final state, `D` end mean, `D x D` end covariance), or None for a model without
        one (files written before end points were learned)."""
        if getattr(self, "end_offsets_", None) is None:
            return None
        state = int(self.end_state_)
        return state, self.coordinates().shifted(np.asarray(self.means_)[state], np.asarray(self.end_offsets_)), np.asarray(self.end_covars_)

    def _hmm_transmat(self) -> np.ndarray:
        """Equivalent HMM transition matrix: self-transition 1 - 1/duration mean (steps)."""
        stay = 1 - self.sample_period_ / np.maximum(self.duration_means_, self.sample_period_)
        transmat = self.normalized_transmat() * (1 - stay)[:, None]
        final = transmat.sum(axis=1) == 0
        transmat[np.arange(self.n_states), np.arange(self.n_states)] = np.where(final, 1.0, stay)
        return transmat
