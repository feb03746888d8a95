from fleet_async.core.base.steps import steps_for


def test_steps_for_covers_the_duration_with_whole_steps():
    assert steps_for(0.3, 0.1) == 3  # 0.3 / 0.1 = 2.9999999999999996
    assert steps_for(0.25, 0.1) == 3
    assert steps_for(0.0, 0.1) == 0
    assert steps_for(1.0, 1 / 240) == 240


def test_steps_for_rounds_a_sim_time_up_to_the_step_that_reaches_it():
    assert steps_for(3.1, 0.1) == 31
    assert steps_for(-0.05, 0.1) == 0
    assert steps_for(-0.25, 0.1) == -2
