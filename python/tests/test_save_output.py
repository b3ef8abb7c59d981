"""delta.save writes a file whole or not at all: a full device is an error (it returned normally
before), the previous file stays, and a symlink at the path is kept with its target replaced."""

import os

import pytest

import delta


def test_save_to_a_full_device_raises(tmp_path):
    full = tmp_path / "full.stl"  # the format comes from the name
    os.symlink("/dev/full", full)
    with pytest.raises(ValueError, match="No space left on device"):
        delta.save(delta.box(), full)


def test_save_keeps_a_symlink_and_replaces_its_target(tmp_path):
    target = tmp_path / "meshes" / "box.stl"
    target.parent.mkdir()
    delta.save(delta.box(), target)
    link = tmp_path / "latest.stl"
    os.symlink(target, link)
    delta.save(delta.icosphere(1), link)
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert delta.load(target).triangle_count == 80
    assert sorted(os.listdir(target.parent)) == ["box.stl"]
