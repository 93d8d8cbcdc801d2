"""Options of the segmentation methods: validation in one place, complete records."""

import dataclasses

import numpy as np
import pytest

from topomap import segment
from topomap.errors import ParameterError
from topomap.io import from_array
from topomap.options import RULES, PaperOptions, TopomapOptions


@pytest.fixture(scope="module")
def two_rooms():
    """Two 3 m x 3 m rooms joined by a 0.9 m door, 0.05 m/px."""
    free = np.zeros((80, 140), bool)
    free[10:70, 10:65] = True
    free[10:70, 75:130] = True
    free[31:49, 65:75] = True
    return from_array(free, resolution=0.05)


# every invalid value of every option: (method, option, value)
BAD = [
    ("topomap", "window", -1),
    ("topomap", "window", "x"),
    ("topomap", "window", float("nan")),
    ("topomap", "window", True),
    ("topomap", "facing", "x"),
    ("topomap", "facing", -0.5),
    ("topomap", "rule", "bogus"),
    ("topomap", "rule", 3),
    ("topomap", "mouths", "yes"),
    ("topomap", "mouths", 1),
    ("topomap", "protrusion_min", 1.5),
    ("topomap", "flat_min", -0.1),
    ("topomap", "rise", -0.2),
    ("topomap", "max_door_width", float("inf")),
    ("topomap", "skeleton_cell", None),
    ("topomap", "min_wall_length", [1.0]),
    ("paper", "erosion_radius", -0.1),
    ("paper", "max_door_search", "far"),
    ("paper", "min_free_branch", None),
]


@pytest.mark.parametrize("method,name,value", BAD, ids=[f"{m}-{n}-{v!r}" for m, n, v in BAD])
def test_bad_value_names_the_option_and_echoes_it(two_rooms, method, name, value):
    with pytest.raises(ParameterError) as info:
        segment(two_rooms, method=method, **{name: value})
    msg = str(info.value)
    assert name in msg
    assert repr(value) in msg


@pytest.mark.parametrize("cls,name,value", [(TopomapOptions, "rule", "bogus"), (TopomapOptions, "reach", -1.0),
                                            (PaperOptions, "wall_band", "wide")])
def test_options_objects_validate_on_creation(cls, name, value):
    with pytest.raises(ParameterError, match=name):
        cls(**{name: value})


@pytest.mark.parametrize("method", ["topomap", "paper", "watershed", "morphological", "distance", "voronoi"])
def test_unknown_keyword_is_a_parameter_error(two_rooms, method):
    with pytest.raises(ParameterError) as info:
        segment(two_rooms, method=method, windw=0.4)
    assert "windw" in str(info.value) and method in str(info.value)


def test_resolution_is_not_a_baseline_option(two_rooms):
    with pytest.raises(ParameterError, match="resolution"):
        segment(two_rooms, method="watershed", resolution=0.1)


def test_options_object_of_the_wrong_method_is_refused(two_rooms):
    with pytest.raises(ParameterError, match="TopomapOptions"):
        segment(two_rooms, method="topomap", options=PaperOptions())


def test_keyword_options_keep_working_and_are_recorded(two_rooms):
    seg = segment(two_rooms, window=0.4)
    assert seg.params["window"] == 0.4
    assert seg.options.window == 0.4
    # the complete record: every field of the options, flat_min included
    assert set(seg.params) == {f.name for f in dataclasses.fields(TopomapOptions)}
    assert seg.params["flat_min"] == 0.45
    assert seg.params == dataclasses.asdict(seg.options)


def test_map_dependent_default_is_recorded_as_it_ran(two_rooms):
    seg = segment(two_rooms)
    assert seg.params["rise"] == pytest.approx(0.1 * (np.sqrt(2) / 2 + 0.5))
    coarse = from_array(two_rooms.free[::4, ::4], resolution=0.2)
    assert segment(coarse).params["rise"] == pytest.approx(0.2 * (np.sqrt(2) / 2 + 0.5))
    assert segment(two_rooms, rise=0.3).params["rise"] == 0.3


def test_options_object_and_keywords_give_the_same_result(two_rooms):
    a = segment(two_rooms, options=TopomapOptions(window=0.4, rule="either"))
    b = segment(two_rooms, window=0.4, rule="either")
    assert a.params == b.params
    np.testing.assert_array_equal(a.labels, b.labels)
    assert [d.segment for d in a.doors] == [d.segment for d in b.doors]


def test_paper_params_are_complete(two_rooms):
    seg = segment(two_rooms, method="paper", erosion_radius=0.05)
    assert seg.params == dataclasses.asdict(PaperOptions(erosion_radius=0.05))


def test_options_are_frozen_and_every_rule_is_accepted():
    opts = TopomapOptions()
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.window = 1.0
    for rule in RULES:
        assert TopomapOptions(rule=rule).rule == rule


def test_every_option_field_is_documented():
    for cls in (TopomapOptions, PaperOptions):
        doc = cls.__doc__
        for f in dataclasses.fields(cls):
            assert f"{f.name} :" in doc, f"{cls.__name__}.{f.name} has no numpydoc entry"


def test_intermediates_are_the_masks_that_ran(two_rooms):
    seg = segment(two_rooms)
    im = seg.intermediates
    for a in (im.free_mask, im.occupied_mask, im.clearance, im.occupied_clearance):
        assert a.shape == two_rooms.shape
    # the preprocessed free mask lies inside free space (eroded); the occupied
    # mask holds every wall cell next to free space (band, then dilated)
    from scipy.ndimage import binary_dilation

    assert not (im.free_mask & ~two_rooms.free).any()
    assert im.free_mask.sum() < two_rooms.free.sum()
    wall_face = binary_dilation(two_rooms.free) & ~two_rooms.free
    assert im.occupied_mask[wall_face].all()
    # the clearance is what the free skeleton graph carries
    for _, _, d in seg.free_graph.edges(data=True):
        p = d["path"]
        np.testing.assert_allclose(d["radius"], im.clearance[p[:, 0], p[:, 1]] * two_rooms.resolution)
    # and the threshold is measured on the occupied clearance
    from topomap.core.skeleton import graph_pixels

    px = graph_pixels(seg.occupied_graph)
    assert seg.threshold == pytest.approx(2 * im.occupied_clearance[px[:, 0], px[:, 1]].mean() * 0.05)
