"""`python -m psph.io.branch`: a checkpoint copied with scene overrides continues under the
new physics, which a plain restart refuses (exit 2)."""

from psph.app import cli
from psph.io.branch import main as branch

RUN = ["--set", "time.end=3e-4", "--quiet"]


def test_a_branched_checkpoint_restarts_with_other_physics(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli.main(["run", "terzaghi_tpi", "--out", str(out), "--set", "time.end=2e-4",
                     "--quiet"]) == 0
    ck = out / "checkpoint.h5"
    other = ["--set", "stabilisation.shepard_every=5"]
    assert cli.main(["run", "terzaghi_tpi", "--restart", str(ck), *other, *RUN]) == 2
    assert "shepard_every" in capsys.readouterr().err
    copy = tmp_path / "branch.h5"
    assert branch([str(ck), str(copy), *other]) == 0
    assert cli.main(["run", "terzaghi_tpi", "--restart", str(copy), *other, "--out",
                     str(tmp_path / "branch"), *RUN]) == 0
    assert branch([str(tmp_path / "missing.h5"), str(copy), *other]) == 2


def test_a_checkpoint_without_a_key_added_since_restarts_with_its_default(tmp_path):
    """A checkpoint written before a scene key existed (its stored scene lacks it)
    restarts when the key is at its default, which keeps the old behaviour; a job chain
    that resubmits across an update must not stop with exit 2."""
    import json

    import h5py

    out = tmp_path / "run"
    assert cli.main(["run", "terzaghi_tpi", "--out", str(out), "--set", "time.end=2e-4",
                     "--quiet"]) == 0
    ck = out / "checkpoint.h5"
    with h5py.File(ck, "r+") as f:
        meta = json.loads(f.attrs["meta"])
        lines = meta["scene"].splitlines()
        kept = [x for x in lines if not x.startswith("pressure_filter_porosity")]
        assert len(kept) == len(lines) - 1
        meta["scene"] = "\n".join(kept) + "\n"
        f.attrs["meta"] = json.dumps(meta)
    assert cli.main(["run", "terzaghi_tpi", "--restart", str(ck), *RUN]) == 0
