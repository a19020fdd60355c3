"""Measured, not assumed: the rendered classes separate on the paper's cues in the expected direction.

Features are the detector's own (jevois_module/ForaNavTrees/foranav_features.py); crops and statistics come
from host_tools.sim.featurecheck. Medians over CROPS_PER_CLASS crops per class, without and with the camera's
sensor effects (blur, noise, JPEG), which soften the needle texture the HOG variance relies on.
"""
import pytest

from host_tools.sim.featurecheck import measure
from host_tools.sim.world import NO_EFFECTS, SENSOR_EFFECTS

CROPS_PER_CLASS = 50
KINDS = ("oil_palm", "coconut", "date_palm", "roof", "road_cross")
# oil palm's median HOG variance at least this many times each look-alike palm's
HOG_VARIANCE_RATIO = {"plain": 4.0, "sensor": 1.5}
HS_SIMILARITY_MARGIN = 0.15  # oil palm's median at least this much above roofs' and road crossings'


@pytest.fixture(scope="module", params=["plain", "sensor"])
def stats(request):
    effects = NO_EFFECTS if request.param == "plain" else SENSOR_EFFECTS
    return request.param, measure(KINDS, CROPS_PER_CLASS, seed=0, effects=effects)


@pytest.mark.parametrize("lookalike", ["coconut", "date_palm"])
def test_that_oil_palm_has_the_higher_bottom_layer_hog_variance(stats, lookalike):
    mode, by_kind = stats
    assert by_kind["oil_palm"].hog_variance_median > \
        HOG_VARIANCE_RATIO[mode] * by_kind[lookalike].hog_variance_median


@pytest.mark.parametrize("lookalike", ["roof", "road_cross"])
def test_that_oil_palm_is_more_similar_in_hue_and_saturation_to_the_template(stats, lookalike):
    _, by_kind = stats
    assert by_kind["oil_palm"].hs_similarity_median > \
        by_kind[lookalike].hs_similarity_median + HS_SIMILARITY_MARGIN
