"""Model files: one self-describing `.npz` holding every learned attribute of an `HSMM`.

Version 2 added `frame_names` for task-parameterised models (`TPHSMM`; files without it, all
version 1 files among them, hold a single-frame `HSMM`) and the demonstrations' end point
(`end_state`, `end_offsets`, `end_covars`; models from files without it retrieve as before,
ending at the final state's mean). Version 3 added `orientation_reference` for skills with
orientation (rotation vectors `rx, ry, rz` relative to it; see `stl_lfd.hsmm.orientation`).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.files import atomic_output
from stl_lfd.hsmm.model import HSMM
from stl_lfd.hsmm.tp import TPHSMM

FORMAT = "stlopt-hsmm"
FORMAT_VERSION = 3
_ARRAYS = ("means_", "covars_", "duration_means_", "duration_stds_", "transmat_", "startprob_")


def save_model(model: HSMM, path: str | Path) -> None:
    """Write `model` to `path` (.npz), atomically (see `stl_lfd.files`)."""
    model._check()
    frames = {"frame_names": np.array(model.frame_names_)} if isinstance(model, TPHSMM) else {}
    end = model.end_target()
    if end is not None:
        frames.update(end_state=end[0], end_offsets=np.asarray(model.end_offsets_), end_covars=end[2])
    if model.orientation is not None:
        frames.update(orientation_reference=model.orientation)
    with atomic_output(path) as temporary:
        np.savez(
            temporary,
            format=FORMAT,
            format_version=FORMAT_VERSION,
            n_states=model.n_states,
            sample_period=model.sample_period_,
            signal_names=np.array(model.signal_names_),
            **{name.rstrip("_"): np.asarray(getattr(model, name)) for name in _ARRAYS},
            **frames,
        )


def load_model(path: str | Path) -> HSMM:
    """Read a model file written by `save_model` (any version up to the current one)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            fields = {name: data[name] for name in data.files}
    except FileNotFoundError:
        raise ModelError(f"{path}: no such model file") from None
    except IsADirectoryError:
        raise ModelError(f"{path}: is a folder, not a model file") from None
    except EOFError:
        raise ModelError(f"{path}: not a model file (it is empty)") from None
    except ValueError as error:
        kind = "it holds Python objects" if "allow_pickle" in str(error) and zipfile.is_zipfile(path) else "not an .npz archive"
        raise ModelError(f"{path}: not a model file ({kind}); write one with stlopt learn") from None
    except (OSError, zipfile.BadZipFile):
        raise ModelError(f"{path}: not a model file (not an .npz archive); write one with stlopt learn") from None
    if str(fields.get("format", "")) != FORMAT:
        raise ModelError(f"{path}: not an stlopt model file (no '{FORMAT}' marker)")
    version = int(fields["format_version"])
    if version > FORMAT_VERSION:
        raise ModelError(f"{path}: model format version {version} is newer than this stlopt understands ({FORMAT_VERSION}); upgrade stlopt")
    missing = [name for name in _ARRAYS if name.rstrip("_") not in fields]
    if missing:
        raise ModelError(f"{path}: the model file lacks '{missing[0].rstrip('_')}'")
    model = TPHSMM(n_states=int(fields["n_states"])) if "frame_names" in fields else HSMM(n_states=int(fields["n_states"]))
    if isinstance(model, TPHSMM):
        model.frame_names_ = [str(name) for name in fields["frame_names"]]
    for name in _ARRAYS:
        setattr(model, name, np.array(fields[name.rstrip("_")], dtype=float))
    model.sample_period_ = float(fields["sample_period"])
    model.signal_names_ = [str(name) for name in fields["signal_names"]]
    model.orientation_reference_ = np.array(fields["orientation_reference"], dtype=float) if "orientation_reference" in fields else None
    if "end_offsets" in fields:
        model.end_state_ = int(fields["end_state"])
        model.end_offsets_ = np.array(fields["end_offsets"], dtype=float)
        model.end_covars_ = np.array(fields["end_covars"], dtype=float)
    try:
        model._check()
    except ModelError as error:
        raise ModelError(f"{path}: {error}") from None
    return model
