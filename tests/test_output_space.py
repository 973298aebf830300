"""A full output file system (issue 15): one line naming the file, the cause and the last
complete checkpoint, exit 74, no `.tmp` left, and the restart from that checkpoint
finishes. The free space is injected (`psph.io.space.free_bytes`); a real 3 MB tmpfs gives
the same line on 2 ranks (README, "Exit codes"), where a collective write that runs out
of space used to leave both ranks spinning inside MPI-IO."""

from psph.app import cli
from psph.io import space
from psph.io.snapshots import read_snapshots

RUN = ["--set", "time.end=6e-4", "--set", "output.interval=1e-4",
       "--set", "checkpoint.every=500", "--quiet"]


def test_full_disk_stops_with_one_line_naming_the_checkpoint_to_continue_from(
        tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"

    def free(directory):  # room until the first checkpoint is complete, then none
        return 10 ** 12 if not (out / "checkpoint.h5").exists() else 1000

    monkeypatch.setattr(space, "free_bytes", free)
    assert cli.main(["run", "terzaghi_tpi", "--out", str(out), *RUN]) == 74
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    assert "no space left on device" in lines[0]
    assert f"--restart {out / 'checkpoint.h5'}" in lines[0] and "(step 500," in lines[0]
    monkeypatch.setattr(space, "free_bytes", lambda directory: 10 ** 12)
    assert cli.main(["run", "terzaghi_tpi", "--restart", str(out / "checkpoint.h5"), *RUN]) == 0


def test_a_failed_checkpoint_write_removes_its_tmp_file(tmp_path, monkeypatch, capsys):
    """A quota the file system does not report: the write itself fails."""
    import psph.app.outputs

    out = tmp_path / "run"

    def failing(path, *args, **kwargs):  # as write_checkpoint names its partial file
        path.with_name(path.name + ".tmp").write_bytes(b"partial")
        raise OSError(122, "Disk quota exceeded")

    monkeypatch.setattr(psph.app.outputs, "write_checkpoint", failing)
    assert cli.main(["run", "terzaghi_tpi", "--out", str(out), *RUN]) == 74
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "Disk quota exceeded" in lines[0], lines
    assert not (out / "checkpoint.h5.tmp").exists()
    assert len(read_snapshots(out / "particles.h5")) >= 1  # the snapshots stay readable
    (out / "checkpoint.h5.tmp").write_bytes(b"stale")  # a write cut short by a kill ...
    monkeypatch.undo()
    assert cli.main(["run", "terzaghi_tpi", "--out", str(out), *RUN]) == 0
    assert not (out / "checkpoint.h5.tmp").exists()  # ... goes at the next start
