"""run/table1.py --ledger: a Table 1 row run in segments, on two machines,
gets its time on the AMRC row's machine (the segments timed there give the
rate per particle-iteration; the others' work is counted at that rate). A
machine is (host, threads, binary): segments of other code are counted at
the rate, not timed. Also: run/table1's resumable rows (row_state,
ledger_line), and the kept ledger behind docs/validation.md's Table 1 at
257:65 giving that table's times."""
import importlib.util
import json
import os
import sys
import tempfile
import unittest

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "run"))
import table1  # noqa: E402

HEAD = ("row\tsegment\twall_seconds\tsteps\tsimulated_seconds\tat_rest\tparticles_mean\titerations\t"
        "date\thost\tstarted\tthreads\tcpu_seconds\tparticles_min\tparticles_max\tbinary\n")


def line(row, seg, wall, mean, its, host, threads, cpu="NA", lo="NA", hi="NA", binary="b1"):
    return "\t".join(str(v) for v in (row, seg, wall, 1, 0.1, False, mean, its, "d", host, 0, threads,
                                      cpu, lo, hi, binary)) + "\n"


# finest: 1e5 particle-iterations on a 16-thread machine, then 5e4 here in
# 50 s: 1e-3 s each here, so 150 s in all. AMRC: 2e4 then 7e3 (the mean
# falls from 20 to 18 as iterations go from 1000 to 1500), all here.
LEDGER = (HEAD
          + line("9-finest", "9-finest", 100, 100, 1000, "big", 16, lo=100, hi=100)
          + line("9-amrc", "9-amrc", 30, 20, 1000, "vm", 1, lo=12, hi=100)
          + "9-amrc\t9-amrc.x\tNA\tNA\tNA\tNA\tNA\tNA\td\tvm\t0\tNA\t# no report\n"
          + line("9-finest", "9-finest.2", 50, 100, 1500, "vm", 1, cpu=45, lo=100, hi=100)
          + line("9-amrc", "9-amrc.2", 10, 18, 1500, "vm", 1, cpu=9, lo=8, hi=14))


class Ledger(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.dir.name, "ledger.tsv")
        with open(self.path, "w") as f:
            f.write(LEDGER)

    def tearDown(self):
        self.dir.cleanup()

    def test_segments_skip_lines_without_a_report(self):
        segs = table1.ledger_segments(self.path)
        self.assertEqual([len(segs["9-finest"]), len(segs["9-amrc"])], [2, 2])
        self.assertIsNone(segs["9-amrc"][0]["cpu"])

    def test_time_on_the_reference_machine(self):
        segs = table1.ledger_segments(self.path)
        self.assertEqual(table1.reference_machine(segs["9-amrc"]), ("vm", 1, "b1"))
        f = table1.campaign_time(segs["9-finest"], ("vm", 1, "b1"))
        self.assertAlmostEqual(f["wall_seconds"], 150.0)
        self.assertAlmostEqual(f["cpu_seconds"], 135.0)
        self.assertAlmostEqual(f["particle_iterations"], 1.5e5)
        self.assertAlmostEqual(f["measured_share"], 1 / 3)
        a = table1.campaign_time(segs["9-amrc"], ("vm", 1, "b1"))
        self.assertAlmostEqual(a["wall_seconds"], 40.0)  # all here: the plain sum
        self.assertIsNone(a["cpu_seconds"])  # the first segment's report had none
        self.assertAlmostEqual(a["particle_iterations"], 2.7e4)
        self.assertIsNone(table1.campaign_time(segs["9-amrc"], ("elsewhere", 4, "b1")))

    def test_rows_take_the_ledger_time_and_particle_range(self):
        rows = [{"size": 9, "mesh": m, "grid": [n, n], "wall_seconds": 1.0, "particles_min": 0,
                 "particles_max": 0, "ledger_row": "%d-%s" % (n, m.lower())}
                for m, n in (("finest", 9), ("AMRC", 9), ("coarsest", 3))]
        table1.apply_ledger(rows, table1.ledger_segments(self.path))
        self.assertAlmostEqual(rows[0]["wall_seconds"], 150.0)
        self.assertEqual((rows[1]["particles_min"], rows[1]["particles_max"]), (8, 100))
        self.assertAlmostEqual(rows[1]["wall_seconds"], 40.0)
        self.assertEqual(rows[2]["wall_seconds"], 1.0)  # not in the ledger: its own report's

    def test_other_code_is_counted_at_the_rate_not_timed(self):
        # 9-amrc-lo reruns the AMRC row with new code (b2), and the finest row
        # gets a segment of b2 too: 2e4 particle-iterations in 10 s, so its
        # 1.7e5 in all take 85 s; its b1 segments count only as work.
        with open(self.path, "a") as f:
            f.write(line("9-amrc-lo", "9-amrc-lo", 12, 18, 1500, "vm", 1, cpu=11, binary="b2")
                    + line("9-finest", "9-finest.3", 10, 100, 1700, "vm", 1, cpu=9, binary="b2"))
        segs = table1.ledger_segments(self.path)
        self.assertEqual(table1.reference_machine(segs["9-amrc-lo"]), ("vm", 1, "b2"))
        rows = [{"size": 9, "mesh": m, "grid": [9, 9], "wall_seconds": 1.0, "particles_min": 0,
                 "particles_max": 0, "ledger_row": name}
                for m, name in (("finest", "9-finest"), ("AMRC", "9-amrc-lo"))]
        table1.apply_ledger(rows, segs)
        self.assertAlmostEqual(rows[0]["wall_seconds"], 85.0)
        self.assertAlmostEqual(rows[0]["measured_share"], 2e4 / 1.7e5)
        self.assertAlmostEqual(rows[1]["wall_seconds"], 12.0)
        self.assertIn("binary b2", rows[0]["machine"])

    def test_a_row_never_run_on_the_reference_machine_is_not_timed(self):
        # 9-amrc-lo ran binary b2, the finest row only b1: no rate for b2.
        with open(self.path, "a") as f:
            f.write(line("9-amrc-lo", "9-amrc-lo", 12, 18, 1500, "vm", 1, cpu=11, binary="b2"))
        rows = [{"size": 9, "mesh": m, "grid": [9, 9], "wall_seconds": 1.0, "particles_min": 0,
                 "particles_max": 0, "ledger_row": name}
                for m, name in (("finest", "9-finest"), ("AMRC", "9-amrc-lo"))]
        table1.apply_ledger(rows, table1.ledger_segments(self.path))
        self.assertIsNone(rows[0]["wall_seconds"])  # not its last segment's report time
        self.assertTrue(rows[0]["untimed"])
        self.assertAlmostEqual(rows[1]["wall_seconds"], 12.0)

    def test_one_whole_segment_elsewhere_keeps_its_report_time(self):
        # SIDE_BY_SIDE runs the coarsest row alone on all threads: one segment,
        # timed whole on another thread count; its report's time stands.
        with open(self.path, "a") as f:
            f.write(line("3-coarsest", "3-coarsest", 4, 9, 200, "vm", 2))
        rows = [{"size": 9, "mesh": m, "grid": [n, n], "wall_seconds": 1.0, "particles_min": 0,
                 "particles_max": 0, "ledger_row": "%d-%s" % (n, m.lower())}
                for m, n in (("finest", 9), ("AMRC", 9), ("coarsest", 3))]
        table1.apply_ledger(rows, table1.ledger_segments(self.path))
        self.assertEqual(rows[2]["wall_seconds"], 1.0)
        self.assertNotIn("untimed", rows[2])

    def test_surface_distance_ignores_sliding_along_the_surface(self):
        # The finest drape a plane z = 0.5 x; the other the same grid moved
        # 0.02 along the plane's normal and 0.3 spacings along the plane:
        # inside, 0.02 from the surface, more from the same material points.
        u = np.linspace(0, 1, 21)
        i, j = np.meshgrid(u, u, indexing="ij")
        ref = np.stack([i, j, 0.5 * i], axis=2)
        normal = np.array([-0.5, 0, 1]) / np.sqrt(1.25)
        along = np.array([1, 0, 0.5]) / np.sqrt(1.25)
        x = ref + 0.02 * normal + 0.3 * 0.05 * along
        d = table1.surface_distance(x, ref)
        np.testing.assert_allclose(d[2:-2, 2:-2], 0.02, rtol=1e-9)
        self.assertGreater(np.linalg.norm(x - ref, axis=2).min(), 0.024)
        # Points moved off the plane's far edge are as far as that edge.
        self.assertGreater(table1.surface_distance(ref + [0.5, 0, 0], ref)[-1, 10], 0.4)

    def test_a_run_folder_names_its_ledger_row(self):
        seg = os.path.join(self.dir.name, "257-amrc-lo.3")
        os.mkdir(seg)
        os.symlink(seg, os.path.join(self.dir.name, "257-amrc"))
        self.assertEqual(table1.ledger_row(os.path.join(self.dir.name, "257-amrc")), "257-amrc-lo")
        self.assertEqual(table1.ledger_row(os.path.join(self.dir.name, "129-finest")), "129-finest")

    @unittest.skipUnless(importlib.util.find_spec("matplotlib"), "matplotlib (run/setup installs it)")
    def test_the_error_picture_is_drawn_from_the_final_frames(self):
        # A 5 x 5 finest drape, AMRC's 1 cm above it, the coarsest's 3 x 3
        # 2 cm above it: a PNG is written.
        def run(name, n, lift, level):
            os.mkdir(os.path.join(self.dir.name, name))
            u = np.linspace(0, 1, n)
            x = np.stack(np.meshgrid(u, u, indexing="ij") + [np.full((n, n), lift)], axis=2)
            with h5py.File(os.path.join(self.dir.name, name, "drape.h5"), "w") as f:
                f["frames/000001/positions"] = x
                f["frames/000001/level"] = np.full((n, n), level, dtype=np.uint8)
            return (name, os.path.join(self.dir.name, name), n)
        runs = [run("5-finest", 5, 0.0, 0), run("5-amrc", 5, 0.01, 1), run("3-coarsest", 3, 0.02, 0)]
        ref = table1.final_positions(runs[0][1])
        path = table1.plot_errors(self.dir.name, 5, [(m, p, n) for (_, p, n), m in
                                                     zip(runs, ("finest", "AMRC", "coarsest"))], ref, 1.0)
        self.assertEqual(path, os.path.join(self.dir.name, "table1-5.png"))
        with open(path, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")

    def test_a_bad_line_names_the_file_and_line(self):
        with open(self.path, "a") as f:
            f.write(line("9-amrc", "9-amrc.3", "fast", 18, 1500, "vm", 1))
        with self.assertRaises(SystemExit) as e:
            table1.ledger_segments(self.path)
        self.assertIn("ledger.tsv:7", str(e.exception))

    def test_a_missing_ledger_is_named(self):
        with self.assertRaises(SystemExit) as e:
            table1.ledger_segments(self.path + ".none")
        self.assertIn("cannot read the ledger", str(e.exception))
        self.assertIn("ledger.tsv.none", str(e.exception))


class ResumableRows(unittest.TestCase):
    """What run/table1 decides per row folder, and the ledger line it appends."""

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.run = os.path.join(self.dir.name, "9-amrc")

    def tearDown(self):
        self.dir.cleanup()

    def write(self, name, text):
        os.makedirs(self.run, exist_ok=True)
        with open(os.path.join(self.run, name), "w") as f:
            f.write(text)

    def report(self, signal="", wall_limit=False):
        self.write("report.json", json.dumps({
            "wall_seconds": 2.5, "steps": 40, "simulated_seconds": 0.04, "at_rest": False,
            "iterations": 900, "threads": 1, "cpu_seconds": 2.4, "stopped_by_signal": signal,
            "stopped_by_wall_limit": wall_limit, "particles_active": {"mean": 20.5, "min": 9, "max": 81}}))

    def test_row_state(self):
        self.assertEqual(table1.row_state(self.run), "new")
        self.write("checkpoint.h5", "")
        self.assertEqual(table1.row_state(self.run), "stopped")  # killed before its report
        self.report(signal="SIGTERM")
        self.assertEqual(table1.row_state(self.run), "stopped")
        self.report(wall_limit=True)
        self.assertEqual(table1.row_state(self.run), "stopped")
        self.report()
        self.assertEqual(table1.row_state(self.run), "done")  # ended by itself, checkpoint or not
        os.remove(os.path.join(self.run, "checkpoint.h5"))
        self.report(signal="SIGINT")
        self.assertEqual(table1.row_state(self.run), "new")  # stopped, but nothing to go on from

    def test_ledger_line_reads_back(self):
        self.report()
        path = os.path.join(self.dir.name, "ledger.tsv")
        with open(path, "w") as f:
            f.write("\t".join(table1.LEDGER_HEAD) + "\n" + table1.ledger_line(self.run, 17, "abc") + "\n")
        seg = table1.ledger_segments(path)["9-amrc"]
        self.assertEqual(len(seg), 1)
        self.assertEqual((seg[0]["wall"], seg[0]["cpu"], seg[0]["iterations"]), (2.5, 2.4, 900))
        self.assertEqual((seg[0]["min"], seg[0]["max"], seg[0]["mean"]), (9, 81, 20.5))
        self.assertEqual(seg[0]["machine"][1:], (1, "abc"))

    def test_a_segment_without_a_report_is_skipped(self):
        os.makedirs(self.run)
        path = os.path.join(self.dir.name, "ledger.tsv")
        with open(path, "w") as f:
            f.write("\t".join(table1.LEDGER_HEAD) + "\n" + table1.ledger_line(self.run, 17, "abc") + "\n")
        self.assertEqual(table1.ledger_segments(path), {})


class Rows(unittest.TestCase):
    """A row of the table from a run's report and final frame."""

    def test_a_row_carries_its_unconverged_steps(self):
        with tempfile.TemporaryDirectory() as d:
            run = os.path.join(d, "5-amrc")
            os.mkdir(run)
            u = np.linspace(0, 1, 5)
            x = np.stack(np.meshgrid(u, u, indexing="ij") + [np.full((5, 5), 0.01)], axis=2)
            with h5py.File(os.path.join(run, "drape.h5"), "w") as f:
                f["frames/000001/positions"] = x
            report = {"grid": [5, 5], "wall_seconds": 1.0, "iterations": 50, "max_penetration": 0.0,
                      "simulated_seconds": 0.1, "steps": 12, "at_rest": True, "unconverged_steps": 3,
                      "final_cost": {"total": 2.0}, "particles_active": {"min": 9, "max": 25, "mean": 20.0}}
            ref = x - [0, 0, 0.01]
            row = table1.table_row(5, "AMRC", run, report, ref, 1.0, 1.0)
            self.assertEqual(row["unconverged_steps"], 3)
            self.assertAlmostEqual(row["quality_error_geometric"], 0.01)
            del report["unconverged_steps"]  # a report from before the field: unknown, not 0
            self.assertIsNone(table1.table_row(5, "AMRC", run, report, ref, 1.0, 1.0)["unconverged_steps"])


class KeptTable(unittest.TestCase):
    """docs/data: the ledger of the Table 1 rows at 257:65 gives the times
    docs/data/table1-257.json (and docs/validation.md) state."""

    def test_the_kept_ledger_gives_the_kept_table(self):
        data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "data")
        segs = table1.ledger_segments(os.path.join(data, "table1-257-ledger.tsv"))
        with open(os.path.join(data, "table1-257.json")) as f:
            rows = json.load(f)["rows"]
        machine = table1.reference_machine(segs[rows[1]["ledger_row"]])
        for r in rows:
            t = table1.campaign_time(segs[r["ledger_row"]], machine)
            self.assertAlmostEqual(t["wall_seconds"], r["wall_seconds"], places=3, msg=r["mesh"])
            self.assertAlmostEqual(t["measured_share"], r["measured_share"], places=6, msg=r["mesh"])
        finest, amrc = rows[0]["wall_seconds"], rows[1]["wall_seconds"]
        self.assertEqual(round(finest / amrc, 2), 6.08)  # the speed-up docs/validation.md states


if __name__ == "__main__":
    unittest.main()
