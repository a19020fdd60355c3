"""Opt-in (-m realdata): the oil-palm detector trained and evaluated on ../shared/data/real."""
import pytest

from host_tools.detection import realdata

pytestmark = [pytest.mark.realdata, pytest.mark.slow]


def test_that_the_real_data_experiment_runs_and_reports_crop_and_frame_figures(tmp_path):
    if not realdata.DEFAULT_REAL.exists():
        pytest.skip("no shared real data")
    result = realdata.run_experiment(seed=0, out=str(tmp_path / "real.npz"), log=lambda m: None)
    crops = result["crops"]
    assert crops["n_pos"] > 50 and crops["n_neg"] > 50
    assert 0.0 <= crops["accuracy"] <= 1.0
    assert result["frames_kluang"]["n_trees"] > 0
    assert (tmp_path / "real.npz").exists()
