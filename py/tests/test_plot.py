"""``leeway.plot`` draws headless (Agg) and returns Figures; importing
leeway does not import matplotlib, and without it a plot names
``pip install matplotlib``."""

from __future__ import annotations

import subprocess
import sys
import warnings

import pytest

import leeway
from conftest import SHIP

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")


def test_importing_leeway_does_not_import_matplotlib() -> None:
    code = "import sys, leeway; assert 'matplotlib' not in sys.modules, 'imported'"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_without_matplotlib_the_error_says_how_to_install() -> None:
    code = (
        "import sys; sys.modules['matplotlib'] = None; sys.modules['matplotlib.pyplot'] = None\n"
        "import leeway.plot\n"
        "try:\n    leeway.plot.residuals(None)\nexcept ImportError as e:\n    print(e)\n"
    )
    o = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "pip install matplotlib" in o.stdout


def test_compare_draws_measured_and_each_theta_with_its_fit(ship_frame) -> None:  # type: ignore[no-untyped-def]
    import leeway.plot

    ship = leeway.Model.load(SHIP)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", leeway.LeewayWarning)
        est = leeway.estimate(ship, ship_frame)
        fig = leeway.plot.compare(ship, {"iv3": est, "nominal": ship.nominal}, ship_frame.head(300))
    axes = fig.get_axes()
    assert len(axes) == len(ship.states)
    for ax, state in zip(axes, ship.states):
        assert ax.get_ylabel() == state
        labels = [line.get_label() for line in ax.get_lines()]
        assert labels[0] == "measured" and len(labels) == 3
        assert labels[1].startswith("iv3 (fit ") and labels[2].startswith("nominal (fit ")
    matplotlib.pyplot.close(fig)


def test_residuals_draws_autocorrelation_and_input_correlations_with_the_band() -> None:
    import leeway.plot
    from test_residuals import BOAT, THETA, boat_data

    boat = leeway.Model.from_str(BOAT)
    analysis = leeway.residuals(boat, THETA, boat_data(500, 1))
    fig = leeway.plot.residuals(analysis)
    axes = fig.get_axes()
    assert len(axes) == len(boat.states) * (1 + len(boat.inputs))
    assert axes[0].get_title() == "u: autocorrelation" and axes[1].get_title() == "u × tau"
    # The autocorrelation's band is a white error's; a cross-correlation's
    # is widened by √P for the colour of the error and the input.
    widened = analysis.band * analysis.input_tests.loc[("u", "tau"), "band"] / analysis.input_band
    for ax, band in zip(axes, [analysis.band, widened]):
        bands = sorted(line.get_ydata()[0] for line in ax.get_lines() if line.get_linestyle() == "--")
        assert bands == pytest.approx([-band, band])
    assert widened >= analysis.band
    matplotlib.pyplot.close(fig)
