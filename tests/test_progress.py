"""Progress: live bars (tqdm) on a terminal only, one line per stage elsewhere and with --quiet;
kernels report through a callback that does not change their results."""

from __future__ import annotations

import io
import pickle

import numpy as np
from conftest import make_scene

from roughcontact import engine, scene as scenes
from roughcontact.cli import main
from roughcontact.physics.adhesion import AdhesionProblem, zeta_grid
from roughcontact.physics.contact import effective_modulus
from roughcontact.physics.quadrature import log_grid
from roughcontact.physics.spectra import self_affine_hrms_factor, self_affine_psd
from roughcontact.physics.volterra import solve_partial_contact
from roughcontact.progress import Reporter, Tick


class Terminal(io.StringIO):
    def isatty(self):
        return True


def _chunked():
    return make_scene(load={"p": {"from": "1 MPa", "to": "10 GPa", "num": 60}},
                      numerics={"points_per_decade": 20, "chunks": {"p": 10}})


def test_a_terminal_gets_live_bars_and_a_log_one_line_per_stage(tmp_path):
    tty, log = Terminal(), io.StringIO()
    engine.run(scenes.from_dict(_chunked()), tmp_path / "a", report=Reporter(tty))
    # work shorter than the interval between progress lines (5 s; 60 s here, so that a loaded machine
    # cannot make it longer): one line per stage
    engine.run(scenes.from_dict(_chunked()), tmp_path / "b", report=Reporter(log, interval=60.0))
    shown = tty.getvalue()
    assert "contact: computing" in shown and "writing" in shown and "block" in shown  # the block writer's bar
    lines = log.getvalue().splitlines()
    assert [line.split(":")[0] for line in lines] == ["[1/2] psd", "[2/2] contact"]
    assert "\r" not in log.getvalue() and all("computed in" in line for line in lines)


def test_quiet_gives_one_line_per_stage(tmp_path, capsys, write_scene):
    path = write_scene(make_scene())
    assert main(["run", str(path), "--outdir", str(tmp_path / "out"), "--quiet"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and err[0].startswith("[1/2] psd: computed in")


def test_kernel_progress_is_counted_and_changes_nothing():
    E_star = effective_modulus(77.2e9, 0.42)
    q = log_grid(7e6, 1.4e9, 20)
    shape = self_affine_psd(q, 0.8, 7e6, 7e6, 1.4e9, 1.0) / self_affine_hrms_factor(0.8, 7e6, 7e6, 1.4e9)
    hs = np.array([5e-10, 12e-10, 16e-10])
    prob = AdhesionProblem(q, hs[:, None] ** 2 * shape, E_star, 1.602176634, zeta_grid(200.0, 6, 1e-10))
    calls = []
    counted = solve_partial_contact(prob, 0.0, np.ones(3), np.zeros(3), progress=calls.append)
    plain = solve_partial_contact(prob, 0.0, np.ones(3), np.zeros(3))
    assert len(calls) >= 3 and set(calls) == {1}  # one tick per march of the root finder
    np.testing.assert_array_equal(counted["K"], plain["K"])


def test_a_tick_sent_to_a_worker_process_does_nothing():
    tty = Terminal()
    tick = Reporter(tty).bar("work", total=3)
    tick()
    remote = pickle.loads(pickle.dumps(tick))
    assert isinstance(remote, Tick)
    remote(5)  # in another process the bar is not there: nothing happens, nothing fails
    assert tick.count == 1 and remote.count == 0 and "work" in tty.getvalue()


def test_a_log_gets_progress_lines_for_long_work_after_its_start_line():
    """Off a terminal, work that lasts past the interval gets lines (here interval 0: one per task),
    preceded by the stage's start line, with what is done, the time so far and what is left;
    with --quiet (bars=False) nothing but the stage lines."""
    log, quiet = io.StringIO(), io.StringIO()
    for stream, bars in ((log, None), (quiet, False)):
        report = Reporter(stream, bars=bars, interval=0.0)
        report.live("[1/1] validation_bem: computing (no result yet)")
        tick = report.bar("writing", total=4, unit="block", initial=1)
        tick()
        tick()
        report.finish()
        report("[1/1] validation_bem: computed in 3 s")
    lines = log.getvalue().splitlines()
    assert lines[0] == "[1/1] validation_bem: computing (no result yet)"
    assert lines[1].startswith("    writing: 2/4 blocks (50%), 0 s so far, about ")
    assert lines[2].startswith("    writing: 3/4 blocks (75%)") and lines[3].endswith("computed in 3 s")
    assert quiet.getvalue().splitlines() == ["[1/1] validation_bem: computed in 3 s"]
