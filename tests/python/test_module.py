"""The Python module against the CLI: numpy array in, image out, equal to vdb_ewa render's image
bit for bit; progress, cancellation and the GIL; bad arguments as Python exceptions.

Run by ctest (tests/CMakeLists.txt) as /usr/bin/python3 -m unittest, with PYTHONPATH at the
built module and VDB_EWA_CLI at the CLI.
"""
import os
import subprocess
import sys
import tempfile
import threading
import time
import unittest
import warnings

import numpy as np

import vdb_ewa

CLI = os.environ.get("VDB_EWA_CLI", "vdb_ewa")

try:
    import pyopenvdb
except ImportError:  # Debian's python3-openvdb; scripts/install-deps.sh --test installs it
    pyopenvdb = None
try:
    import OpenImageIO as oiio
except ImportError:
    oiio = None


def read_exr(path):
    """The EXR's channels as float32 (height, width, channels) and its channel names."""
    image = oiio.ImageInput.open(path)
    pixels = np.asarray(image.read_image(format="float"))
    names = image.spec().channelnames
    image.close()
    return pixels, names


def cli(*args):
    """Run the CLI; return (exit code, stderr)."""
    done = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=600)
    return done.returncode, done.stderr


def smoke_block(shape=(20, 24, 28), seed=1):
    """A lumpy block of density inside an empty border."""
    rng = np.random.default_rng(seed)
    a = np.zeros(shape, np.float32)
    a[3:-3, 4:-4, 5:-3] = rng.random((shape[0] - 6, shape[1] - 8, shape[2] - 8))
    return a


# A sheared, scaled, translated index-to-world map in column-vector form.
MATRIX = np.array([[0.1, 0.02, 0.0, 1.0], [0.0, 0.12, 0.0, -0.5], [0.01, 0.0, 0.09, 0.3], [0.0, 0.0, 0.0, 1.0]])
OPTIONS = dict(res="96x64", translate=(2, 1, 6), lookat=(2, 0.9, 1.5), light=[(1, 1, 0), (-1, 0.5, 0, 0.2, 0.3, 0.6)],
               absorb=(0.1, 0.2, 0.3), scatter=1.2)
CLI_OPTIONS = ["--res", "96x64", "--translate", "2,1,6", "--lookat", "2,0.9,1.5", "--light", "1,1,0", "--light",
               "-1,0.5,0,0.2,0.3,0.6", "--absorb", "0.1,0.2,0.3", "--scatter", "1.2"]


class Module(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.cloud = os.path.join(cls.dir, "cloud.vdb")
        code, err = cli("make-grid", "cloud", cls.cloud)
        assert code == 0, err

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.dir, name)

    # --- images equal to the CLI's ---

    @unittest.skipIf(pyopenvdb is None or oiio is None, "needs Debian's python3-openvdb and python3-openimageio")
    def test_array_renders_as_the_cli_renders_the_same_grid_from_a_file(self):
        a = smoke_block()
        # The same grid written by pyopenvdb, OpenVDB's own binding: its matrix is the transpose.
        g = pyopenvdb.FloatGrid()
        g.copyFromArray(a)
        g.transform = pyopenvdb.createLinearTransform(MATRIX.T.tolist())
        g.name = "density"
        pyopenvdb.write(self.path("block.vdb"), grids=[g])
        code, err = cli(self.path("block.vdb"), self.path("block_cli.exr"), *CLI_OPTIONS, "--exr-type", "float", "-q")
        self.assertEqual(code, 0, err)
        expected, names = read_exr(self.path("block_cli.exr"))
        frame = vdb_ewa.render(vdb_ewa.from_array(a, MATRIX), **OPTIONS)
        self.assertEqual(frame.beauty.shape, (64, 96, 4))
        self.assertEqual(frame.beauty.dtype, np.float32)
        self.assertGreater(frame.beauty[..., 3].max(), 0.5)  # not an empty frame
        np.testing.assert_array_equal(frame.beauty, expected[..., :4])
        np.testing.assert_array_equal(frame.aovs["depth"], expected[..., names.index("Z")])
        # A transposed (row-vector) matrix is refused, not silently misplaced.
        with self.assertRaisesRegex(vdb_ewa.ValueError, "last row must be 0, 0, 0, 1"):
            vdb_ewa.from_array(a, MATRIX.T)

    @unittest.skipIf(oiio is None, "needs Debian's python3-openimageio")
    def test_file_renders_and_writes_as_the_cli(self):
        args = ["--res", "80x60", "--translate", "1.5,0.8,4.5", "--aov", "shadow,emission", "--emission", "0.2",
                "--exr-type", "float"]
        code, err = cli(self.cloud, self.path("cloud_cli.exr"), *args, "-q")
        self.assertEqual(code, 0, err)
        expected, names = read_exr(self.path("cloud_cli.exr"))
        frame = vdb_ewa.render(self.cloud, res="80x60", translate=(1.5, 0.8, 4.5), aov=["shadow", "emission"], emission=0.2,
                               exr_type="float")
        np.testing.assert_array_equal(frame.beauty, expected[..., :4])
        self.assertEqual(sorted(frame.aovs), ["depth", "emission", "shadow"])
        for layer in ("shadow", "emission"):
            columns = [names.index("%s.%s" % (layer, c)) for c in "RGB"]
            np.testing.assert_array_equal(frame.aov(layer), expected[..., columns])
        self.assertGreater(frame.aov("emission").max(), 0.0)
        # write(): the same pixels and the same header (but for the time and the input's spelling).
        frame.write(self.path("cloud_py.exr"))
        written, written_names = read_exr(self.path("cloud_py.exr"))
        self.assertEqual(written_names, names)
        np.testing.assert_array_equal(written, expected)
        spec = lambda p: {a.name: a.value for a in oiio.ImageInput.open(p).spec().extra_attribs
                          if a.name.startswith("vdb_ewa/") and a.name not in ("vdb_ewa/render-seconds", "vdb_ewa/peak-memory-mb",
                                                                                  "vdb_ewa/peak-bytes-per-active-voxel")}
        self.assertEqual(spec(self.path("cloud_py.exr")), spec(self.path("cloud_cli.exr")))
        self.assertEqual(frame.metadata["vdb_ewa/exr-type"], "float")
        # The footprint samples and slab composites at each image level: every pixel where the
        # footprints are narrower than image_lod's, the coarser levels where they are wider, the
        # same counts as the header's.
        stats = frame.stats
        self.assertEqual(stats["footprint_samples_by_level"], (stats["footprint_samples"], 0, 0, 0))
        self.assertEqual(stats["slab_composites_by_level"][1:], (0, 0, 0))
        near = vdb_ewa.render(self.cloud, res="80x60", translate=(0.3, 0.2, 0.9), image_lod=1)
        by_level = near.stats["footprint_samples_by_level"]
        self.assertGreater(sum(by_level[1:]), 0)
        self.assertEqual(sum(by_level), near.stats["footprint_samples"])
        self.assertEqual(near.metadata["vdb_ewa/footprint-samples-by-level"], ",".join(str(n) for n in by_level))
        self.assertEqual(near.metadata["vdb_ewa/image-lod"], "1")
        self.assertGreater(sum(near.stats["slab_composites_by_level"][1:]), 0)  # composited at a level too (on)
        self.assertEqual(near.metadata["vdb_ewa/slab-composites-by-level"], ",".join(str(n) for n in near.stats["slab_composites_by_level"]))
        apart = vdb_ewa.render(self.cloud, res="80x60", translate=(0.3, 0.2, 0.9), image_lod=1, image_lod_composite="off")
        self.assertEqual(apart.stats["slab_composites_by_level"][1:], (0, 0, 0))
        self.assertEqual(apart.metadata["vdb_ewa/image-lod-composite"], "off")
        # Larger pixels (--pixel-size): from close by, one sample an n x n block, said in stats and the header.
        self.assertEqual(frame.stats["pixel_size"], 1)
        big = vdb_ewa.render(self.cloud, res="160x120", translate=(0.3, 0.2, 0.9), pixel_size=4, pixel_size_blur=1)
        self.assertGreater(big.stats["pixel_size"], 1)
        self.assertEqual(big.metadata["vdb_ewa/pixel-size-blur"], "1")
        self.assertEqual(big.metadata["vdb_ewa/pixel-size-used"], str(big.stats["pixel_size"]))
        self.assertEqual((big.width, big.height), (160, 120))

    def test_index_to_world_places_a_voxel_where_the_matrix_says(self):
        # One voxel at index (3, 5, 7) of a 2x-scaled grid translated by (10, 20, 30): world (16, 30, 44).
        a = np.zeros((8, 8, 8), np.float32)
        a[3, 5, 7] = 1.0
        m = np.array([[2, 0, 0, 10], [0, 2, 0, 20], [0, 0, 2, 30], [0, 0, 0, 1]], float)
        grid = vdb_ewa.from_array(a, m)
        np.testing.assert_allclose(grid.world_centre, (16, 30, 44))
        frame = vdb_ewa.render(grid, res="41x41", camera="ortho", frame=8, translate=(16, 30, 54), lookat=(16, 30, 44))
        alpha = frame.beauty[..., 3]
        self.assertGreater(alpha[20, 20], 0.1)
        rows, columns = np.mgrid[0:41, 0:41]
        # The alpha's centroid at the image centre (pixel 20: 8 / 41 world units a pixel).
        self.assertAlmostEqual(float((alpha * rows).sum() / alpha.sum()), 20.0, delta=0.1)
        self.assertAlmostEqual(float((alpha * columns).sum() / alpha.sum()), 20.0, delta=0.1)
        # Half the voxel's depth (2 units) is in front of its centre: the depth is 10 less up to a voxel.
        self.assertGreater(float(frame.aovs["depth"][20, 20]), 8.0)
        self.assertLess(float(frame.aovs["depth"][20, 20]), 10.5)

    def test_transformed_moves_the_grid_as_its_matrix_would(self):
        # An object's transform (rotation, uneven scale, move) after the grid's own map: the same
        # grid as the one whose map is the product.
        a = smoke_block()
        move = np.array([[0, -1.2, 0, 2], [1, 0, 0, -1], [0, 0, 0.7, 0.5], [0, 0, 0, 1]], float)
        moved = vdb_ewa.from_array(a, MATRIX).transformed(move)
        direct = vdb_ewa.from_array(a, move @ MATRIX)
        np.testing.assert_allclose(moved.world_centre, direct.world_centre, atol=1e-9)
        self.assertAlmostEqual(moved.voxel_length, abs(np.linalg.det((move @ MATRIX)[:3, :3])) ** (1 / 3), places=12)
        options = dict(res="64x48", lookat=direct.world_centre, translate=np.add(direct.world_centre, (1, 2, 5)))
        expected = vdb_ewa.render(direct, **options).beauty
        self.assertGreater(expected[..., 3].max(), 0.3)
        np.testing.assert_allclose(vdb_ewa.render(moved, **options).beauty, expected, atol=1e-4)
        unmoved = vdb_ewa.render(vdb_ewa.from_array(a, MATRIX), **options).beauty
        self.assertGreater(np.abs(unmoved - expected).max(), 0.1)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "last row must be 0, 0, 0, 1"):
            moved.transformed(move.T)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "4x4"):
            moved.transformed(np.eye(3))

    @unittest.skipIf(pyopenvdb is None or oiio is None, "needs Debian's python3-openvdb and python3-openimageio")
    def test_volumes_summed_with_their_own_velocities_render_as_the_cli(self):
        # Two blocks, one with a velocity grid v, one still: each attached before the sum
        # (Grid.with_velocity_grid, Grid.with_added_volume) is the CLI's --add-volume with
        # --velocity-grid, bit for bit; no warning that the shutter changes nothing; the blur shows.
        files = []
        for name, offset, velocity in (("a.vdb", (0, 0, 0), (30.0, 0.0, 0.0)), ("b.vdb", (0.8, 0.3, 0), None)):
            g = pyopenvdb.FloatGrid()
            g.copyFromArray(smoke_block((12, 14, 16), 3))
            g.transform = pyopenvdb.createLinearTransform([[0.1, 0, 0, 0], [0, 0.1, 0, 0], [0, 0, 0.1, 0], [*offset, 1]])
            g.name = "density"
            grids = [g]
            if velocity:
                v = pyopenvdb.Vec3SGrid()
                v.name = "v"
                v.transform = g.transform
                v.fill((0, 0, 0), (11, 13, 15), velocity, True)
                grids.append(v)
            pyopenvdb.write(self.path(name), grids=grids)
            files.append(self.path(name))
        shot = ["--res", "64x48", "--translate", "0.9,0.7,4", "--lookat", "0.9,0.7,0.8", "--shutter", "-0.25,0.25"]
        code, err = cli(files[1], self.path("two_cli.exr"), "--add-volume", files[0], "--velocity-grid", "v", *shot,
                        "--exr-type", "float", "-q")
        self.assertEqual(code, 0, err)
        expected, _ = read_exr(self.path("two_cli.exr"))
        summed = vdb_ewa.open(files[1]).with_added_volume(vdb_ewa.open(files[0]).with_velocity_grid("v"))
        options = dict(res="64x48", translate=(0.9, 0.7, 4), lookat=(0.9, 0.7, 0.8), shutter=(-0.25, 0.25))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            frame = vdb_ewa.render(summed, **options)
        np.testing.assert_array_equal(frame.beauty, expected[..., :4])
        self.assertEqual([str(w.message) for w in caught], [])
        still = vdb_ewa.render(vdb_ewa.open(files[1]).with_added_volume(vdb_ewa.open(files[0])), **options)
        self.assertGreater(np.abs(still.beauty - frame.beauty).max(), 0.02)
        # The CLI: no volume with the grid is an error; a still main input with a moving added one is not.
        code, err = cli(files[1], self.path("none.exr"), "--velocity-grid", "v", *shot, "-q")
        self.assertEqual(code, 3, err)
        self.assertIn("no grid named 'v'", err)
        # A volume of its own medium: the keywords are the CLI's --add-volume-material, bit for bit.
        code, err = cli(files[1], self.path("own_cli.exr"), "--add-volume", files[0], "--add-volume-material",
                        "absorb=0.5,0.3,0.1 scatter=1", *shot, "--exr-type", "float", "-q")
        self.assertEqual(code, 0, err)
        expected, _ = read_exr(self.path("own_cli.exr"))
        own = vdb_ewa.open(files[1]).with_added_volume(vdb_ewa.open(files[0]), absorb=(0.5, 0.3, 0.1), scatter=1)
        np.testing.assert_array_equal(vdb_ewa.render(own, **options).beauty, expected[..., :4])
        self.assertGreater(np.abs(vdb_ewa.render(own, **options).beauty - still.beauty).max(), 0.02)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "absorb: expected a number or"):
            vdb_ewa.open(files[1]).with_added_volume(vdb_ewa.open(files[0]), absorb=(1, 2))
        with self.assertRaisesRegex(vdb_ewa.ValueError, "scatter must be in"):
            vdb_ewa.open(files[1]).with_added_volume(vdb_ewa.open(files[0]), scatter=-1)

    @unittest.skipIf(pyopenvdb is None or oiio is None, "needs Debian's python3-openvdb and python3-openimageio")
    def test_array_velocity_blurs_as_the_cli_blurs_the_same_vectors_from_a_file(self):
        a = smoke_block((16, 18, 20), 4)
        v = np.zeros(a.shape + (3,), np.float32)
        v[..., 0] = 6.0
        v[..., 2] = np.linspace(-3.0, 3.0, a.shape[2], dtype=np.float32)  # varies along k
        g = pyopenvdb.FloatGrid()
        g.copyFromArray(a)
        g.transform = pyopenvdb.createLinearTransform(MATRIX.T.tolist())
        g.name = "density"
        w = pyopenvdb.Vec3SGrid()
        w.copyFromArray(v)
        w.transform = g.transform
        w.name = "v"
        pyopenvdb.write(self.path("moving_block.vdb"), grids=[g, w])
        shot = ["--res", "64x48", "--translate", "2,1,6", "--lookat", "2,0.9,1.5"]
        code, err = cli(self.path("moving_block.vdb"), self.path("moving_cli.exr"), *shot, "--velocity-grid", "v", "--exr-type", "float", "-q")
        self.assertEqual(code, 0, err)
        expected, _ = read_exr(self.path("moving_cli.exr"))
        options = dict(res="64x48", translate=(2, 1, 6), lookat=(2, 0.9, 1.5))
        frame = vdb_ewa.render(vdb_ewa.from_array(a, MATRIX, velocity=v), **options)
        np.testing.assert_array_equal(frame.beauty, expected[..., :4])
        self.assertGreater(np.abs(frame.beauty - vdb_ewa.render(vdb_ewa.from_array(a, MATRIX), **options).beauty).max(), 0.02)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "velocity: expected an array of the density's shape and 3 components"):
            vdb_ewa.from_array(a, MATRIX, velocity=v[..., :2])
        with self.assertRaisesRegex(vdb_ewa.ValueError, "velocity: expected an array of the density's shape"):
            vdb_ewa.from_array(a, MATRIX, velocity=v[1:])

    # --- progress, cancellation, the GIL ---

    def long_render(self, **kw):
        # About 0.7 s here (960x540 took 0.26 s: a cancel at 0.2 s could come after the end).
        return vdb_ewa.render(vdb_ewa.from_array(smoke_block((96, 96, 96), 2)), res="1920x1080", translate=(48, 48, 150),
                              quality="high", threads=2, **kw)

    # --- a scene that stays loaded ---

    def test_a_scene_renders_what_render_renders_and_keeps_the_light(self):
        views = [dict(translate=(0.3, 0.2, 1.2), lookat=(0.0, 0.0, 0.0)), dict(translate=(-0.8, 0.3, 1.0), lookat=(0.0, 0.0, 0.0))]
        scene = vdb_ewa.Scene(self.cloud, res=(96, 72), aov="shadow")
        self.assertEqual(scene.options["res"], (96, 72))
        for k, view in enumerate(views + views[:1]):
            frame = scene.render(**view)
            cold = vdb_ewa.render(self.cloud, res=(96, 72), aov="shadow", **view)
            np.testing.assert_array_equal(frame.beauty, cold.beauty)
            np.testing.assert_array_equal(frame.aov("shadow"), cold.aov("shadow"))
            if k > 0:
                self.assertGreater(frame.stats["light_maps_reused"], 0)
                self.assertGreater(frame.stats["light_rays_reused"], 0)
            if k == 2:
                self.assertEqual(frame.stats["light_rays_marched"], 0)  # back where the first render looked
        # A render's keywords override the scene's for that render only; the light's direction
        # makes its maps anew.
        lit = scene.render(light=(-0.5, 0.7, 0.2, 0.7, 0.7, 0.7), **views[0])
        np.testing.assert_array_equal(lit.beauty, vdb_ewa.render(self.cloud, res=(96, 72), light=(-0.5, 0.7, 0.2, 0.7, 0.7, 0.7), **views[0]).beauty)
        self.assertEqual(lit.stats["light_maps_reused"], 0)
        again = scene.render(**views[0])
        self.assertEqual(again.stats["light_maps_reused"], 0)  # the scene's own light again: made anew, then kept
        scene.clear()
        with self.assertRaisesRegex(vdb_ewa.ValueError, "color: a Scene's grids are given when it is made"):
            scene.render(color="density")
        with self.assertRaisesRegex(vdb_ewa.ValueError, "shadowstep"):
            scene.render(shadowstep=-1)
        with self.assertRaises(vdb_ewa.Cancelled):
            scene.render(progress=lambda p: p >= 0)
        np.testing.assert_array_equal(scene.render(**views[1]).beauty, vdb_ewa.render(self.cloud, res=(96, 72), **views[1]).beauty)

    def test_a_progressive_render_gives_a_coarse_frame_then_the_one_returned(self):
        view = dict(translate=(0.3, 0.2, 1.2), lookat=(0.0, 0.0, 0.0))
        scene = vdb_ewa.Scene(self.cloud, res=(128, 96), aov="shadow")
        images = []
        frame = scene.render(progressive=lambda f: images.append((f, threading.get_ident())), **view)
        self.assertEqual([f.coarse for f, _ in images], [True, False])
        self.assertEqual([f.stats["coarse_scale"] for f, _ in images], [4, 1])
        self.assertEqual({t for _, t in images}, {threading.get_ident()})  # on the calling thread
        self.assertIs(images[1][0], frame)
        coarse = images[0][0]
        self.assertEqual((coarse.width, coarse.height), (128, 96))
        self.assertEqual(coarse.aov("shadow").shape, (96, 128, 3))
        np.testing.assert_array_equal(frame.beauty, vdb_ewa.render(self.cloud, res=(128, 96), aov="shadow", **view).beauty)
        self.assertLess(np.abs(coarse.beauty[..., 3] - frame.beauty[..., 3]).mean(), 0.1 * frame.beauty[..., 3].mean())
        # True for the coarse frame cancels the rest; a frame render() returned stays as it was.
        with self.assertRaises(vdb_ewa.Cancelled):
            scene.render(progressive=lambda f: f.coarse, **view)
        # Answered after the asked image is done (a slow callback, a busy machine), True still cancels.
        with self.assertRaises(vdb_ewa.Cancelled):
            scene.render(progressive=lambda f: time.sleep(0.5) or f.coarse, **view)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "progressive: expected a callable"):
            scene.render(progressive=3)
        with self.assertRaisesRegex(ZeroDivisionError, ""):
            scene.render(progressive=lambda f: 1 / 0, **view)
        np.testing.assert_array_equal(scene.render(**view).beauty, frame.beauty)

    def test_progress_rises_to_100_on_the_calling_thread(self):
        calls = []
        frame = self.long_render(progress=lambda p: calls.append((p, threading.get_ident())))
        percents = [p for p, _ in calls]
        self.assertGreater(len(percents), 2, percents)
        self.assertEqual(percents, sorted(percents))
        self.assertEqual(percents[-1], 100)
        self.assertEqual({t for _, t in calls}, {threading.get_ident()})
        self.assertGreater(frame.beauty[..., 3].max(), 0.1)

    def test_the_calling_thread_waits_without_spinning(self):
        # One render thread: the process's CPU time is about its wall time. A caller that polled
        # without sleeping (once, when no progress callback was given) doubled it on two cores.
        for progress in (None, lambda p: None):
            cpu, wall = time.process_time(), time.monotonic()
            vdb_ewa.render(vdb_ewa.from_array(smoke_block((96, 96, 96), 2)), res="960x540", translate=(48, 48, 150),
                           quality="high", threads=1, progress=progress)
            cpu, wall = time.process_time() - cpu, time.monotonic() - wall
            self.assertGreater(wall, 0.2)
            self.assertLess(cpu, 1.25 * wall, (progress, cpu, wall))

    def test_cancel_from_another_thread(self):
        token = vdb_ewa.CancelToken()
        t0 = time.monotonic()
        threading.Timer(0.2, token.cancel).start()
        with self.assertRaises(vdb_ewa.Cancelled):
            self.long_render(cancel=token)
        self.assertLess(time.monotonic() - t0, 0.2 + 1.0)
        self.assertTrue(token.cancelled)

    def test_progress_returning_true_cancels_and_its_exceptions_propagate(self):
        with self.assertRaises(vdb_ewa.Cancelled):
            self.long_render(progress=lambda p: p >= 0)
        def fails(p):
            raise ZeroDivisionError("from the callback")
        with self.assertRaisesRegex(ZeroDivisionError, "from the callback"):
            self.long_render(progress=fails)

    def test_the_gil_is_released_while_rendering(self):
        def count_for(work):
            """How far a Python thread counts while work() runs, and work()'s seconds."""
            counts = {"n": 0}
            stop = threading.Event()
            def count():
                while not stop.is_set():
                    counts["n"] += 1
            thread = threading.Thread(target=count)
            thread.start()
            time.sleep(0.05)  # the counter runs before the clock starts
            try:
                n0, t0 = counts["n"], time.monotonic()
                work()
                n1, t1 = counts["n"], time.monotonic()
            finally:
                stop.set()
                thread.join()
            return n1 - n0, t1 - t0
        alone, alone_seconds = count_for(lambda: time.sleep(0.3))  # the counter's own rate
        rate = alone / alone_seconds
        during, seconds = count_for(self.long_render)
        # Released, the counter shares two cores with the render's two threads (a quarter of one
        # at least); held, it would count only between the render's setup and its end.
        self.assertGreater(seconds, 0.2)
        self.assertGreater(during, 0.15 * rate * seconds, (during, rate, seconds))

    # --- bad arguments ---

    def cli_message(self, *args):
        code, err = cli(self.cloud, self.path("never.exr"), *args)
        self.assertNotEqual(code, 0)
        line = err.strip().splitlines()[-1]
        self.assertTrue(line.startswith("vdb_ewa: "), line)
        return line[len("vdb_ewa: "):].replace(" (see vdb_ewa --help)", "")

    def test_bad_options_raise_the_cli_messages(self):
        for kw, args in [(dict(refine="x"), ["--refine", "x"]), (dict(refine=9), ["--refine", "9"]),
                         (dict(res="0x10"), ["--res", "0x10"]), (dict(aa="blur"), ["--aa", "blur"]),
                         (dict(light=(1, 2)), ["--light", "1,2"]), (dict(focal=30, fov=40), ["--focal", "30", "--fov", "40"])]:
            with self.subTest(kw=kw):
                with self.assertRaises(vdb_ewa.ValueError) as raised:
                    vdb_ewa.render(self.cloud, **kw)
                self.assertIsInstance(raised.exception, ValueError)  # the built-in too
                self.assertIsInstance(raised.exception, vdb_ewa.Error)
                self.assertEqual(str(raised.exception), self.cli_message(*args))
        with self.assertRaisesRegex(vdb_ewa.ValueError, "unknown keyword argument 'colour'"):
            vdb_ewa.render(self.cloud, colour="Cd")
        with self.assertRaisesRegex(vdb_ewa.ValueError, "progress: expected a callable"):
            vdb_ewa.render(self.cloud, progress=3)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "cancel: expected a vdb_ewa.CancelToken"):
            vdb_ewa.render(self.cloud, cancel=True)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "grid: expected a vdb_ewa.Grid"):
            vdb_ewa.render(42)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "translate: expected a string, number"):
            vdb_ewa.render(self.cloud, translate={"x": 1})

    def test_scattering_keywords_shape_the_light(self):
        # --anisotropy and --multiple-scattering as keywords, as the CLI takes them: 0 and 1 are
        # the default image bit for bit; forward scattering and octaves change it; the path
        # tracer renders; the options are in the metadata; a bad value raises the CLI's line.
        options = dict(res="48x32", translate=(1, 0.5, 4), light=(-1, 0.3, -1, 1, 1, 1), gain=0)
        base = vdb_ewa.render(self.cloud, **options)
        np.testing.assert_array_equal(vdb_ewa.render(self.cloud, anisotropy=0, multiple_scattering=1, **options).beauty, base.beauty)
        forward = vdb_ewa.render(self.cloud, anisotropy=0.6, **options)
        self.assertGreater(forward.beauty[..., 0].sum(), 1.2 * base.beauty[..., 0].sum())  # seen against the light
        octaves = vdb_ewa.render(self.cloud, multiple_scattering=3, octave_scatter=0.7, **options)
        self.assertGreater(octaves.beauty[..., 0].sum(), 1.2 * base.beauty[..., 0].sum())
        self.assertEqual(octaves.metadata["vdb_ewa/multiple-scattering"], "3")
        self.assertEqual(octaves.metadata["vdb_ewa/octave-scatter"], "0.7")
        self.assertEqual(forward.metadata["vdb_ewa/anisotropy"], "0.6")
        traced = vdb_ewa.render(self.cloud, method="pathtrace", samples=2, bounces=2, **options)
        self.assertEqual(traced.metadata["vdb_ewa/bounces"], "2")
        self.assertGreater(traced.beauty[..., 3].max(), 0.5)
        with self.assertRaises(vdb_ewa.ValueError) as raised:
            vdb_ewa.render(self.cloud, anisotropy=1.5)
        self.assertEqual(str(raised.exception), self.cli_message("--anisotropy", "1.5"))

    def test_bad_inputs_raise_typed_exceptions(self):
        with self.assertRaises(vdb_ewa.IoError) as raised:
            vdb_ewa.open(self.path("missing.vdb"))
        self.assertIsInstance(raised.exception, OSError)
        self.assertIn("missing.vdb", str(raised.exception))
        with open(self.path("truncated.vdb"), "wb") as f:
            with open(self.cloud, "rb") as whole:
                f.write(whole.read()[:200])
        with self.assertRaises(vdb_ewa.IoError):
            vdb_ewa.render(self.path("truncated.vdb"))
        with self.assertRaisesRegex(vdb_ewa.InputError, "nosuchgrid"):
            vdb_ewa.open(self.cloud, "nosuchgrid")
        for bad, message in [(np.zeros((4, 4)), "expected a 3D array"), (np.zeros((0, 4, 4)), "empty")]:
            with self.assertRaisesRegex(vdb_ewa.ValueError, message):
                vdb_ewa.from_array(bad)
        for m, message in [(np.eye(3), "4x4"), (np.zeros((4, 4)), "last row"), (np.diag([1, 1, 0, 1]), "singular"),
                           (np.diag([np.nan, 1, 1, 1]), "not finite")]:
            with self.assertRaisesRegex(vdb_ewa.ValueError, message):
                vdb_ewa.from_array(np.ones((2, 2, 2)), m)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "emission_grid: the grid came from an array"):
            vdb_ewa.render(vdb_ewa.from_array(np.ones((2, 2, 2))), emission_grid="flame")
        with self.assertRaises(vdb_ewa.BudgetError) as raised:
            dense = np.random.default_rng(3).random((128, 128, 128), np.float32) + 0.1  # 2M voxels, no tiles
            vdb_ewa.render(vdb_ewa.from_array(dense), max_memory="64M", res="64x64", translate=(64, 64, 300), cull=False)
        self.assertIsInstance(raised.exception, MemoryError)

    def test_write_refuses_what_the_cli_refuses(self):
        frame = vdb_ewa.render(self.cloud, res="32x24", translate=(1.5, 0.8, 4.5))
        with open(self.cloud, "rb") as f:
            before = f.read()
        os.symlink(self.cloud, self.path("cloud_link.exr"))
        with self.assertRaisesRegex(vdb_ewa.ValueError, "same file as the input"):
            frame.write(self.path("cloud_link.exr"))
        with open(self.cloud, "rb") as f:
            self.assertEqual(f.read(), before)
        with self.assertRaises(vdb_ewa.IoError):
            frame.write(os.path.join(self.dir, "no", "such", "folder", "out.exr"))
        with self.assertRaisesRegex(vdb_ewa.ValueError, "unsupported output format"):
            frame.write(self.path("out.xyz"))
        frame.write(self.path("out.png"))  # 8-bit through the display transform, as the CLI
        self.assertTrue(os.path.getsize(self.path("out.png")) > 0)
        with self.assertRaisesRegex(vdb_ewa.ValueError, "was not rendered"):
            frame.aov("shadow")

    def test_output_options_apply_when_the_frame_is_written(self):
        # preview, display and view belong to the file: render() keeps them for write().
        frame = vdb_ewa.render(self.cloud, res="32x24", translate=(1.5, 0.8, 4.5), preview=self.path("preview.png"),
                               display="sRGB", view="Un-tone-mapped")
        frame.write(self.path("with_preview.exr"))
        self.assertTrue(os.path.isfile(self.path("preview.png")))
        frame.write(self.path("display.png"))
        self.assertTrue(os.path.isfile(self.path("display.png")))
        with self.assertRaisesRegex(vdb_ewa.ValueError, "--preview writes a .png file"):
            vdb_ewa.render(self.cloud, res="8x8", translate=(1.5, 0.8, 4.5), preview=self.path("p.jpg")).write(self.path("x.exr"))
        # deep=True: the flat beauty is in output_space too (a deep image is composited at one
        # sample a pixel: supersample=1's).
        kw = dict(res="32x24", translate=(1.5, 0.8, 4.5), output_space="lin_rec709")
        np.testing.assert_array_equal(vdb_ewa.render(self.cloud, deep=True, **kw).beauty,
                                      vdb_ewa.render(self.cloud, supersample=1, **kw).beauty)
        # Emitter arrays must lie on the density's voxels.
        with self.assertRaisesRegex(vdb_ewa.ValueError, "temperature: expected an array of the density's shape"):
            vdb_ewa.from_array(np.ones((4, 4, 4)), temperature=np.ones((4, 4, 5)))
        with self.assertRaisesRegex(vdb_ewa.ValueError, "emission: expected an array"):
            vdb_ewa.from_array(np.ones((4, 4, 4)), emission=[[1, 2], [3]])

    def test_warnings_reach_python(self):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            frame = vdb_ewa.render(self.cloud, res="16x16", translate=(1.5, 0.8, 4.5), emission_color=(1, 0, 0))
        self.assertTrue(any(issubclass(w.category, vdb_ewa.RenderWarning) and "--emission-color changes nothing" in str(w.message)
                            for w in caught), [str(w.message) for w in caught])
        self.assertTrue(any("--emission-color" in w for w in frame.warnings))

    # --- documentation ---

    def test_help_documents_every_keyword(self):
        doc = vdb_ewa.render.__doc__
        keywords = vdb_ewa._keywords()
        self.assertGreater(len(keywords), 60)
        for keyword, option, kind, description in keywords:
            self.assertIn("    %s (%s): " % (keyword, kind), doc)
            self.assertTrue(description, keyword)
        for name in ("refine_emission", "lod_error", "max_memory", "exr_type", "quality", "translate"):
            self.assertIn(name, [k[0] for k in keywords])

    def test_stub_matches_the_module(self):
        stub = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python", "make_stub.py")
        done = subprocess.run([sys.executable, stub, "--check"], capture_output=True, text=True)
        self.assertEqual(done.returncode, 0, done.stdout + done.stderr)


if __name__ == "__main__":
    unittest.main()
