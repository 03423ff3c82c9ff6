"""The studies' C timer (studies.timing): several models' right-hand sides timed in one program, and ratios
taken batch by batch."""
import pytest

from codegen.pipeline import generate
from codegen.scene import default_scene
from studies.timing import BATCHES, Timing, ratios, time_rhs_side_by_side


def test_ratios_pair_the_batches():
    assert ratios(Timing((2.0, 9.0, 4.0)), Timing((1.0, 3.0, 4.0))).samples == (2.0, 3.0, 1.0)
    with pytest.raises(ValueError, match="one side-by-side run"):
        ratios(Timing((1.0, 2.0)), Timing((1.0,)))


def test_models_side_by_side_need_different_names_and_a_count_each():
    model = generate(default_scene(1), name="short")
    with pytest.raises(ValueError, match="different names"):
        time_rhs_side_by_side([model, model], [10, 10])
    with pytest.raises(ValueError, match="one calls count per model"):
        time_rhs_side_by_side([model], [10, 10])
    with pytest.raises(ValueError, match="calls must be >= 1"):
        time_rhs_side_by_side([model], [0])


@pytest.mark.slow      # a 16-link chain's derivation (a study's harness)
def test_each_model_is_timed_on_its_own_rhs():
    """A 16-link chain's rhs (about 14 times the operations of a 1-link chain's) is timed slower in the same program:
    the median of the batches' ratios is above 5 (the same rhs timed twice would give 1; one batch disturbed by
    another process on the machine does not move the median); every model gets one sample per batch."""
    short, long = generate(default_scene(1), name="short"), generate(default_scene(16), name="long")
    ops = [{f.name: f.ops.total for f in m.functions}["forward_dynamics"] for m in (short, long)]
    assert ops[1] > 10 * ops[0]
    a, b = time_rhs_side_by_side([short, long], [20000, 2000])
    assert a.runs == b.runs == BATCHES and min(a.samples) > 0
    per_batch = sorted(ratios(b, a).samples)
    assert per_batch[len(per_batch) // 2] > 5
