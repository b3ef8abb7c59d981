"""Checkpoints of a delta.dem.World: World.save / World.load and pickling continue a run bit
for bit, state_digest compares runs (also with the C++ tool's --json), and a bad file is a
delta.Error."""

import pickle

import numpy as np
import pytest

import delta


def settled(steps):
    scenario = delta.dem.settle(count=20, seed=3)
    scenario.world.run(steps)
    return scenario.world


def assert_same(a, b):
    assert a.step_count == b.step_count and a.time == b.time
    assert a.state_digest == b.state_digest
    # Bit for bit: every field of every particle, as bytes.
    assert a.particles.tobytes() == b.particles.tobytes()
    assert a.contacts.tobytes() == b.contacts.tobytes()


def test_save_load_and_continue_bit_for_bit(tmp_path):
    whole = settled(1500)
    stopped = settled(1500)
    assert len(stopped.contacts) > 0  # springs and forces carry into the next step
    path = tmp_path / "run.delta"
    stopped.save(str(path))
    loaded = delta.dem.World.load(str(path))
    assert_same(stopped, loaded)
    whole.run(100)
    loaded.run(100)
    assert_same(whole, loaded)


def test_pickle_continues_bit_for_bit():
    whole = settled(1500)
    copy = pickle.loads(pickle.dumps(settled(1500)))
    assert_same(whole, copy)
    whole.run(50)
    copy.run(50)
    assert_same(whole, copy)


def test_state_digest_is_that_of_the_cli(cli_json):
    world = settled(0)
    world.run(200)
    expected = cli_json("dem", "settle", "--particles", 20, "--seed", 3, "--steps", 200,
                        "--quiet")
    assert world.state_digest == expected["state_digest"]
    assert len(world.state_digest) == 16 and int(world.state_digest, 16) >= 0


def test_bad_files_are_errors(tmp_path):
    foreign = tmp_path / "foreign.delta"
    foreign.write_text("solid x\n")
    with pytest.raises(delta.Error, match="not a Δ DEM checkpoint"):
        delta.dem.World.load(str(foreign))
    path = tmp_path / "run.delta"
    settled(10).save(str(path))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(delta.Error, match="truncated"):
        delta.dem.World.load(str(path))
    flipped = bytearray(data)
    flipped[-3] ^= 0x40
    path.write_bytes(bytes(flipped))
    with pytest.raises(delta.Error, match="corrupt"):
        delta.dem.World.load(str(path))
    with pytest.raises(delta.Error, match="missing"):
        delta.dem.World.load(str(tmp_path / "missing.delta"))


def test_paths_are_paths_and_an_embedded_nul_is_refused(tmp_path, monkeypatch):
    # A string with a NUL went to the C calls whole, which stopped at the NUL: 'a\0b.delta' wrote
    # ./a and 'a\0zzz' read it back, without an error.
    monkeypatch.chdir(tmp_path)
    world = settled(10)
    with pytest.raises(TypeError):
        world.save("a\x00b.delta")
    world.save(tmp_path / "run.delta")  # an os.PathLike too
    assert_same(world, delta.dem.World.load(tmp_path / "run.delta"))
    with pytest.raises(TypeError):
        delta.dem.World.load("run.delta\x00zzz")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.delta"]
