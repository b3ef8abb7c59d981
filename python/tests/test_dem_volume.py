"""delta.dem with the volume contact law (contact_model='volume'): the parameter, the scenarios
against the C++ tool, the contacts' couples and volumes, and what the law refuses."""

import pytest

import delta


def test_contact_model_is_a_parameter():
    parameters = delta.dem.Parameters(time_step=1e-5, epsilon=1e-3, filter_distance=1e-3,
                                      stiffness=1e4)
    assert parameters.contact_model == "point"
    parameters.contact_model = "volume"
    assert parameters.contact_model == "volume" and "contact_model='volume'" in repr(parameters)
    with pytest.raises(delta.Error, match="neither point nor volume"):
        parameters.contact_model = "spring"
    made = delta.dem.Parameters(1e-5, 1e-3, 1e-3, 1e4, contact_model="volume")
    assert delta.dem.World(made).parameters.contact_model == "volume"


def test_two_particles_rebound_as_asked_and_as_the_cli(cli_json):
    scenario = delta.dem.two_particles(restitution=0.5, contact_model="volume")
    assert scenario.world.parameters.contact_model == "volume"
    world = scenario.world
    touched = False
    for _ in range(scenario.steps):
        world.step()
        contacts = world.contacts
        if len(contacts):
            touched = True
            # One overlap region: its volume, the couple of its moment, along x.
            assert len(contacts) == 1 and contacts["volume"][0] > 0
            assert contacts["overlap"][0] and contacts["force"][0, 0] <= 0  # 0 once parting
    assert touched
    meter = scenario.restitution_meter
    assert meter.separated and meter.restitution == pytest.approx(0.5, rel=0.02)
    expected = cli_json("dem", "two-particles", "--restitution", 0.5, "--contact-model", "volume",
                        "--quiet")
    assert expected["contact_model"] == "volume"
    assert meter.restitution == expected["restitution"]
    assert world.time == expected["time"]


def test_settle_with_the_volume_law_equals_the_cli(cli_json):
    scenario = delta.dem.settle(count=8, seed=3, contact_model="volume")
    assert scenario.world.obstacle_count == 5  # delta.dem.open_box_walls
    scenario.run(40)
    expected = cli_json("dem", "settle", "--particles", 8, "--seed", 3, "--steps", 40,
                        "--contact-model", "volume", "--quiet")
    assert scenario.world.time == expected["time"]


def test_what_the_volume_law_refuses():
    with pytest.raises(delta.Error, match="sphere"):
        delta.dem.settle(count=8, kind="sphere", contact_model="volume")
    world = delta.dem.World(delta.dem.Parameters(1e-5, 1e-3, 1e-3, 1e4, contact_model="volume"))
    with pytest.raises(delta.Error, match="closed"):
        world.add_obstacle(delta.quad(0.1, 0.1))
    with pytest.raises(delta.Error, match="closed"):
        world.add_obstacle(delta.dem.open_box(0.1, 0.1, 0.1))
    walls = delta.dem.open_box_walls(0.1, 0.1, 0.1, 0.0, 0.01)
    pieces = delta.dem.funnel_walls(0.05, 0.2, 0.1, 0.3, 48, 0.01)
    assert len(walls) == 5 and len(pieces) == 48
    assert all(wall.triangles.shape == (12, 3) for wall in walls + pieces)
    for wall in walls + pieces:
        world.add_obstacle(wall)
    assert world.obstacle_count == 53
