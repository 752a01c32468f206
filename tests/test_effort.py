"""Effort presets: each resolves to its documented options, explicit options override them."""

import dataclasses

import pytest

import placement
from placement.cli import build_parser
from placement.cli.plan import _print_validation, plan_options
from placement.effort import EFFORT_NAMES, EFFORTS, effort_options
from placement.finalists import FinalistOptions
from placement.plan import LOCAL_SWARM, Planner
from placement.simselect import SearchOptions
from placement.validation import ValidationOptions, validate_layout
from simulation import Room

ROOM = Room.techtile()


def test_presets_resolve_to_their_documented_values():
    assert EFFORT_NAMES == ("quick", "default", "thorough")
    default = effort_options("default")
    assert (default.search, default.finalists, default.validation) == (
        SearchOptions(), FinalistOptions(), ValidationOptions())  # fmt: skip
    quick, thorough = effort_options("quick"), effort_options("thorough")
    # the values placement.effort's docstring names
    assert quick.search.draws == 1 and quick.search.exact_draws == 1
    assert quick.search.chains == 4 and quick.search.evaluations == 1000
    assert quick.search.fine_halvings == 1 and quick.search.fine_spacings is None
    # one lattice, the candidate spacing halved once, in any room
    assert quick.search.fine_spacings_for(ROOM) == (0.2,)
    hall = Room(size=(24.0, 16.0, 6.0), name="hall")
    assert quick.search.spacing_for(hall) == 0.9 and quick.search.fine_spacings_for(hall) == (0.45,)
    assert SearchOptions().fine_spacings_for(hall) == (0.45, 0.225, 0.1125)
    assert quick.finalists.draws == 3 and quick.validation.realizations == 8
    assert quick.validation.held_out_realizations == 0 and quick.validation.field_draws == 3
    assert quick.validation.mount_draws == 2
    assert thorough.search.draws == 6 and thorough.search.exact_draws == 4
    assert thorough.search.chains == 16 and thorough.search.evaluations == 9000
    assert thorough.search.fine_optima == 3
    assert thorough.finalists == FinalistOptions(count=3, draws=24)
    assert thorough.validation.field_draws == 20
    for name in EFFORT_NAMES:
        planner = Planner(ROOM, 8, effort=name, progress=False)
        preset = EFFORTS[name]
        assert planner.search == preset.search and planner.finalists == preset.finalists
        assert planner.validation == preset.validation and planner.swarm == LOCAL_SWARM
        assert planner.settings().effort == name


def test_explicit_options_override_the_preset_and_bad_names_are_value_errors():
    mine = SearchOptions(chains=2)
    planner = Planner(ROOM, 8, effort="thorough", search=mine, progress=False)
    assert planner.search is mine  # the whole phase's options, as given
    assert planner.finalists == EFFORTS["thorough"].finalists  # the others: the preset's
    for bad in ("fast", None, 3, ["quick"]):
        with pytest.raises(ValueError, match="effort: expected one of quick, default, thorough"):
            Planner(ROOM, 8, effort=bad, progress=False)


def test_the_command_line_changes_single_values_of_the_preset():
    args = build_parser().parse_args(["plan", "--effort", "quick", "--finalist-draws", "7",
                                      "--search-chains", "3"])  # fmt: skip
    opts = plan_options(args)
    quick = EFFORTS["quick"]
    assert opts["effort"] == "quick"
    assert opts["finalists"] == dataclasses.replace(quick.finalists, draws=7)
    assert opts["search"] == dataclasses.replace(quick.search, chains=3)
    assert opts["validation"] == quick.validation  # no flag: the preset's, not a CLI default
    plain = plan_options(build_parser().parse_args(["plan"]))
    assert plain["validation"] == ValidationOptions() and plain["search"] == SearchOptions()
    assert plain["finalists"] == FinalistOptions()
    refine = plan_options(build_parser().parse_args(["plan", "--refine-layouts", "2"]))
    assert refine["search"] == SearchOptions(fine_optima=2)
    with pytest.raises(ValueError, match=r"^--refine-layouts: .*\[1, 1000\].*got 0"):
        plan_options(build_parser().parse_args(["plan", "--refine-layouts", "0"]))


def test_the_command_line_prints_the_field_figure_first(capsys):
    a = ROOM.corners_layout()
    opt = ValidationOptions(realizations=2, held_out_realizations=1, random_nodes=10,
                            mount_draws=1, field_draws=2)  # fmt: skip
    _print_validation(validate_layout(ROOM, a, rng=0, options=opt, nodes=ROOM.grid()[::9]))
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("field (2 draws of 10 random tags, anchors mounted within 3 cm)")
    assert ": median " in lines[0] and lines[0].index("median") < lines[0].index("sigma")
    assert lines[1].startswith("validation, 2 realizations at the 30 nodes")
    assert lines[2].startswith("  line of sight: 100.0 % of the nodes see 4 or more anchors")


def test_the_sweep_takes_the_preset_too():
    with pytest.raises(ValueError, match="effort"):
        placement.sweep(ROOM, [4], effort="fast", progress=False)
