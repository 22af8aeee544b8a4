"""One demonstration: the floor under a learned state's spread (stl_lfd.hsmm.spread)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stl_lfd.errors import ModelError
from stl_lfd.hsmm import learn_from_folder
from stl_lfd.hsmm.spread import ONE_DEMONSTRATION, MinimumSpread, parse_min_spread, widened
from tests.conftest import ROOT

ONE = ROOT / "demos" / "reorient_insert" / "demo_01.csv"


def test_widening_raises_only_the_directions_narrower_than_the_floor():
    covariance = np.diag([1e-8, 0.04**2, 1e-8])
    rotation = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    turned = rotation @ covariance @ rotation.T
    result = widened(turned, np.full(3, 0.005))
    values = np.sort(np.linalg.eigvalsh(result))
    assert values == pytest.approx([0.005**2, 0.005**2, 0.04**2])
    assert widened(np.diag([0.01, 0.02]), np.array([0.01, 0.01])) == pytest.approx(np.diag([0.01, 0.02]))  # already wider


def test_one_demonstration_is_widened_and_several_are_not():
    single, _ = learn_from_folder(ONE, 6)
    assert single.min_spread == ONE_DEMONSTRATION
    for covariance in single.covars_:
        assert np.linalg.eigvalsh(covariance).min() >= min(ONE_DEMONSTRATION.position, ONE_DEMONSTRATION.angle) ** 2 * 0.999
    assert np.all(single.duration_stds_ >= 0.1 * single.duration_means_ - 1e-12)
    unfloored, _ = learn_from_folder(ONE, 6, min_spread=None)
    assert np.sqrt(np.linalg.eigvalsh(unfloored.covars_[0]).min()) < 0.002  # one demonstration alone: about a millimetre
    assert np.allclose(unfloored.means_, single.means_)  # the floor changes the spread, not the states
    several, _ = learn_from_folder(ROOT / "demos" / "reorient_insert", 6)
    assert several.min_spread is None


def test_the_spread_option_reads_units():
    assert parse_min_spread("auto") == "auto" and parse_min_spread("none") is None
    spread = parse_min_spread("2mm,1.5deg,20%")
    assert spread == MinimumSpread(pytest.approx(0.002), pytest.approx(math.radians(1.5)), pytest.approx(0.2))
    assert parse_min_spread("0.01m,0.1rad,5%") == MinimumSpread(0.01, 0.1, 0.05)
    for text in ("5mm,3deg", "5,3,10", "5mm,3deg,-10%", "5mm,3deg,nan%", "5cm,3deg,10%"):
        with pytest.raises(ModelError, match=rf"'min_spread' {text}: give auto, none, or a position"):
            parse_min_spread(text)  # from Python, the setting's name; `stlopt learn` says --min-spread (test_misuse)


def test_learning_from_one_csv_says_it_widened_the_states(tmp_path):
    from typer.testing import CliRunner

    from stl_lfd.cli import app

    result = CliRunner().invoke(app, ["learn", str(ONE), "-o", str(tmp_path / "one.npz")])
    assert result.exit_code == 0, result.output
    assert "states widened to at least 5 mm and 5 degrees, durations to 10 % of their means (--min-spread)" in result.stderr
    assert "(1 demonstration, K = 6" in result.stderr
    bad = CliRunner().invoke(app, ["learn", str(ONE), "-o", str(tmp_path / "x.npz"), "--min-spread", "5mm"])
    assert bad.exit_code != 0 and "Traceback" not in bad.output and not (tmp_path / "x.npz").exists()
