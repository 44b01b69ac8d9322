"""The Python module against the tool: the same bake through `import prtsub` and through the
`prtsub` binary gives the same asset; arrays are views of the library's data; a white furnace
renders to its closed form; errors are the tool's one-line messages as Python exceptions.
Run by ctest with PYTHONPATH at the built module and PRTSUB_BINARY at the tool."""
import math
import os
import subprocess
import tempfile
import unittest

import numpy as np

import prtsub

BINARY = os.environ["PRTSUB_BINARY"]


def box_on_ground():
    """A unit cube standing on a 6x6 ground quad: shadows, so transfer varies (numpy arrays)."""
    ground = [(-3, 0, -3), (3, 0, -3), (3, 0, 3), (-3, 0, 3)]
    cube = [(x, y, z) for x in (-0.5, 0.5) for y in (0.01, 1.01) for z in (-0.5, 0.5)]
    vertices = np.array(ground + cube, dtype=np.float64)
    faces = [(0, 2, 1), (0, 3, 2)]  # ground, facing +y
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    for a, b, c, d in quads:
        a, b, c, d = (4 + i for i in (a, b, c, d))
        faces += [(a, b, c), (a, c, d)]
    return vertices, np.array(faces, dtype=np.int64)


def icosphere_on_ground():
    """A level-2 icosphere (320 triangles) resting on a 2x2-cell ground grid: enough faces to simplify."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
         (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(2):
        mid, g = {}, []
        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                mid[k] = len(v) - 1
            return mid[k]
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = g
    n = len(v)
    for j in range(3):
        for i in range(3):
            v.append((-3 + 3 * i, -1, -3 + 3 * j))
    for j in range(2):
        for i in range(2):
            a = n + 3 * j + i
            f += [(a, a + 3, a + 4), (a, a + 4, a + 1)]  # facing +y
    return np.array(v, dtype=np.float64), np.array(f, dtype=np.int64)


def write_obj(path, vertices, faces):
    with open(path, "w") as f:
        for v in vertices:
            f.write("v %.17g %.17g %.17g\n" % tuple(v))
        for t in faces:
            f.write("f %d %d %d\n" % tuple(i + 1 for i in t))


class BakeTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.vertices, self.faces = box_on_ground()

    def tearDown(self):
        self.dir.cleanup()

    def path(self, name):
        return os.path.join(self.dir.name, name)

    def test_the_same_bake_as_the_tool(self):
        write_obj(self.path("box.obj"), self.vertices, self.faces)
        options = dict(order=3, rays=64, seed=7, fit="lsq")
        ours = prtsub.bake(self.vertices, self.faces, **options)
        subprocess.run([BINARY, "bake", self.path("box.obj"), "-o", self.path("tool.ply"), "--order", "3", "--rays", "64",
                        "--seed", "7", "--fit", "lsq"], check=True, capture_output=True)
        tool = prtsub.load(self.path("tool.ply"))
        self.assertEqual(ours.transfer.shape, (tool.vertices.shape[0], 9))
        np.testing.assert_array_equal(ours.faces, tool.faces)
        np.testing.assert_allclose(ours.vertices, tool.vertices, atol=1e-6)
        # The tool's asset holds float32: the same values to float rounding.
        np.testing.assert_allclose(ours.transfer, tool.transfer, rtol=0, atol=1e-6 * np.abs(ours.transfer).max())
        self.assertGreater(np.ptp(ours.transfer[:, 0]), 0.1, "the box shadows the ground")
        self.assertEqual(ours.stats["triangles_out"], len(self.faces))
        self.assertGreater(ours.stats["rays"], 64 * len(ours.vertices))

    def test_arrays_are_views_of_the_asset(self):
        a = prtsub.bake(self.vertices, self.faces, order=2, rays=16, fit="point")
        t = a.transfer
        self.assertFalse(t.flags["OWNDATA"])
        self.assertTrue(np.shares_memory(t, a.transfer), "two reads are one buffer")
        t[0, 0] = 42.0  # writing the view writes the asset
        prtsub.save(a, self.path("a.ply"))
        self.assertAlmostEqual(prtsub.load(self.path("a.ply")).transfer[0, 0], 42.0, places=5)
        for name in ("vertices", "normals", "faces", "source_face"):
            array = getattr(a, name)
            self.assertFalse(array.flags["WRITEABLE"], name)
            self.assertFalse(array.flags["OWNDATA"], name)
        with self.assertRaises(ValueError):
            a.faces[0, 0] = 1
        del a  # the views keep the asset alive
        self.assertEqual(t[0, 0], 42.0)

    def test_a_white_furnace_renders_to_its_closed_form(self):
        # An open quad facing +z, unoccluded: its transfer is exact (the control variate), and
        # under constant radiance 1 a surface of albedo A leaves radiance A.
        quad = np.array([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], dtype=np.float64)
        a = prtsub.bake(quad, np.array([(0, 1, 2, 3)]), order=3, rays=8, fit="point")
        camera = dict(eye=(0, 0, 4), target=(0, 0, 0), up=(0, 1, 0), fov=60)
        frame = prtsub.render(a, prtsub.constant((1, 1, 1)), size=(40, 30), camera=camera, albedo=0.5)
        self.assertEqual(frame.shape, (30, 40, 4))
        self.assertEqual(frame.dtype, np.float32)
        covered = frame[..., 3] > 0
        self.assertGreater(covered.sum(), 100)
        np.testing.assert_allclose(frame[covered][:, :3], 0.5, atol=1e-5)
        self.assertTrue(np.all(frame[~covered][:, :3] == 0))
        # A directional sun delivering irradiance pi (L = pi delta_d, so l_i = pi y_i(d)) on the
        # exact transfer A_l y_i(n): radiance A * sum_l A_l (2l+1)/(4 pi) P_l(cos theta), which
        # order 3 (bands 0-2) truncates to A (1/4 + c/2 + 5/16 P_2(c)); 1.0625 A overhead.
        for degrees in (0, 60, 85):
            c = math.cos(math.radians(degrees))
            want = 0.5 * (0.25 + 0.5 * c + 5 / 16 * (3 * c * c - 1) / 2)
            d = (0, math.sin(math.radians(degrees)), c)
            sun = prtsub.render(a, prtsub.sun(d), size=(40, 30), camera=camera, albedo=0.5)
            np.testing.assert_allclose(sun[covered][:, :3], want, atol=1e-5)

    def test_ao_assets_and_gltf(self):
        a = prtsub.bake(self.vertices, self.faces, signal="ao", rays=32, fit="point")
        self.assertIsNone(a.transfer)
        self.assertEqual(a.ao.shape, (len(a.vertices),))
        self.assertTrue(np.all((a.ao >= 0) & (a.ao <= 1)))
        prtsub.save(a, self.path("ao.glb"), compress=True)
        b = prtsub.load(self.path("ao.glb"))
        self.assertEqual(b.signal, "ao")
        np.testing.assert_allclose(b.ao, a.ao, atol=1e-6)

    def test_bounces_add_light_as_the_tool_does(self):
        write_obj(self.path("box.obj"), self.vertices, self.faces)
        ours = prtsub.bake(self.vertices, self.faces, order=2, rays=32, fit="point", bounces=2, albedo=0.5)
        subprocess.run([BINARY, "bake", self.path("box.obj"), "-o", self.path("b.ply"), "--order", "2", "--rays", "32", "--fit", "point",
                        "--bounces", "2", "--albedo", "0.5"], check=True, capture_output=True)
        np.testing.assert_allclose(ours.transfer, prtsub.load(self.path("b.ply")).transfer, rtol=0, atol=1e-6)
        direct = prtsub.bake(self.vertices, self.faces, order=2, rays=32, fit="point")
        self.assertEqual(ours.stats["bounces"], 2)
        self.assertGreater(ours.transfer[:, 0].sum(), direct.transfer[:, 0].sum())

    def test_coloured_bounces_are_rgb_as_the_tool_bakes_them(self):
        write_obj(self.path("box.obj"), self.vertices, self.faces)
        ours = prtsub.bake(self.vertices, self.faces, order=2, rays=32, fit="point", bounces=2, albedo=(0.9, 0.5, 0.2))
        subprocess.run([BINARY, "bake", self.path("box.obj"), "-o", self.path("c.ply"), "--order", "2", "--rays", "32", "--fit", "point",
                        "--bounces", "2", "--albedo", "0.9,0.5,0.2"], check=True, capture_output=True)
        tools = prtsub.load(self.path("c.ply"))
        self.assertEqual((ours.channels, tools.channels), (3, 3))
        self.assertEqual(ours.transfer.shape, (len(ours.vertices), 12))
        np.testing.assert_allclose(ours.transfer, tools.transfer, rtol=0, atol=1e-6)
        np.testing.assert_allclose(tools.albedo, np.tile([0.9, 0.5, 0.2], (len(ours.vertices), 1)), atol=1e-7)
        # Each channel is the grey bake at that channel's albedo.
        for c, a in enumerate((0.9, 0.5, 0.2)):
            grey = prtsub.bake(self.vertices, self.faces, order=2, rays=32, fit="point", bounces=2, albedo=a)
            np.testing.assert_allclose(ours.transfer[:, 4 * c:4 * c + 4], grey.transfer, rtol=0, atol=1e-12)
        frame = prtsub.render(ours, prtsub.sky(), size=(32, 32))
        self.assertEqual(frame.shape, (32, 32, 4))
        with self.assertRaises(Exception):
            prtsub.render(ours, prtsub.sky(), size=(32, 32), albedo=0.5)

    def test_order_auto_chooses_as_the_tool_does(self):
        sphere, ours, tools = self.bake_both("order", ["--order", "auto", "--rays", "16", "--fit", "point"], order="auto", rays=16,
                                             fit="point")
        self.assertEqual(ours.order, tools.order)
        self.assertEqual(ours.stats["order"], tools.order)
        np.testing.assert_allclose(ours.transfer, tools.transfer, rtol=0, atol=1e-6)

    def bake_both(self, name, cli, **options):
        """The module's bake and the tool's of the same icosphere on the ground, as (ours, the tool's asset)."""
        sphere = prtsub.mesh(*icosphere_on_ground())
        write_obj(self.path(name + ".obj"), *icosphere_on_ground())
        subprocess.run([BINARY, "bake", self.path(name + ".obj"), "-o", self.path(name + ".ply")] + cli, check=True, capture_output=True)
        return sphere, prtsub.bake(sphere, **options), prtsub.load(self.path(name + ".ply"))

    def test_a_budget_below_the_input_simplifies_as_the_tool_does(self):
        sphere, ours, tool = self.bake_both("s", ["--rays", "16", "--refine", "adaptive", "--budget", "150", "--min-angle", "10"],
                                            rays=16, refine="adaptive", budget=150, min_angle=10)
        self.assertEqual(len(ours.faces), 150)
        np.testing.assert_array_equal(ours.faces, tool.faces)
        np.testing.assert_allclose(ours.transfer, tool.transfer, rtol=0, atol=1e-6)
        self.assertTrue(any(k == "simplified" for k, _ in ours.metadata))
        with self.assertRaises(prtsub.InputError):
            prtsub.bake(sphere, refine="adaptive", budget=100, simplify_metric="sideways")

    def test_both_ways_reaches_the_budget_as_the_tool_does(self):
        sphere, ours, tool = self.bake_both("a", ["--rays", "16", "--refine", "auto", "--budget", "300", "--auto-share", "0.7",
                                                  "--auto-cycles", "2", "--auto-cycle-share", "0.05"],
                                            rays=16, refine="auto", budget=300, auto_share=0.7, auto_cycles=2, auto_cycle_share=0.05)
        self.assertEqual(len(ours.faces), 300)
        np.testing.assert_array_equal(ours.faces, tool.faces)
        np.testing.assert_allclose(ours.transfer, tool.transfer, rtol=0, atol=1e-6)
        self.assertTrue(any(k == "auto" and "further cycle(s) (share 0.050000)" in v for k, v in ours.metadata), ours.metadata)
        with self.assertRaises(prtsub.InputError):
            prtsub.bake(sphere, refine="auto")  # no budget

    def test_errors_are_the_tools_one_line_messages(self):
        with open(self.path("bad.obj"), "w") as f:
            f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
        tool = subprocess.run([BINARY, "bake", self.path("bad.obj"), "-o", self.path("x.ply")], capture_output=True, text=True)
        self.assertEqual(tool.returncode, 1)
        with self.assertRaises(prtsub.InputError) as raised:
            prtsub.load_mesh(self.path("bad.obj"))
        self.assertEqual("prtsub: error: " + str(raised.exception) + "\n", tool.stderr)
        self.assertIsInstance(raised.exception, ValueError)
        self.assertIsInstance(raised.exception, prtsub.Error)
        with self.assertRaises(prtsub.IoError) as missing:
            prtsub.load(self.path("missing.ply"))
        self.assertTrue(str(missing.exception).startswith(self.path("missing.ply") + ": "))
        self.assertIsInstance(missing.exception, OSError)
        with self.assertRaises(TypeError):
            prtsub.bake(self.vertices, self.faces, raes=3)
        with self.assertRaises(prtsub.InputError):
            prtsub.bake(self.vertices, self.faces, order=11)
        with self.assertRaises(prtsub.InputError):
            prtsub.bake(self.vertices[:, :2], self.faces)
        self.assertFalse(os.path.exists(self.path("x.ply")))



class SphericalGaussianTest(unittest.TestCase):
    def test_lobes_are_fitted_non_negative_and_lights_project_in_closed_form(self):
        v, f = box_on_ground()
        mesh = prtsub.mesh(v, f)
        c = prtsub.sg_transfer(mesh, 12, rays=128)
        self.assertEqual(c.shape, (mesh.num_vertices, 12))
        self.assertGreaterEqual(c.min(), 0.0)
        signed = prtsub.sg_transfer(mesh, 12, rays=128, non_negative=False)
        self.assertLess(signed.min(), 0.0)  # the clamp binds: a signed fit carves out the lower half
        # A constant light: each lobe sees 4π e^{-λ} sinh(λ)/λ of it, λ = ln 2 / (1 - cos(θ/2)), θ = √(4π/12).
        lam = math.log(2) / (1 - math.cos(math.sqrt(4 * math.pi / 12) / 2))
        lobe = 4 * math.pi * math.exp(-lam) * math.sinh(lam) / lam
        light = prtsub.sg_light(prtsub.constant([0.5, 1, 2]), 12)
        self.assertEqual(light.shape, (12, 3))
        np.testing.assert_allclose(light, np.tile([0.5 * lobe, lobe, 2 * lobe], (12, 1)), rtol=1e-9)
        # As SH of order 4, the lobes relight exactly as they do under any order-4 light.
        sh = prtsub.sg_to_sh(c, 4)
        self.assertEqual(sh.shape, (mesh.num_vertices, 16))
        light = prtsub.random_light(3)
        np.testing.assert_allclose(sh @ light.coefficients(4)[:, 0], c @ prtsub.sg_light(light, 12, order=4)[:, 0], rtol=1e-9, atol=1e-12)
        with self.assertRaisesRegex(ValueError, "between 4 and 64 lobes"):
            prtsub.sg_transfer(mesh, 3)

    def test_a_baked_sg_asset_saves_loads_and_renders_as_its_lobes_relight(self):
        v, f = box_on_ground()
        mesh = prtsub.mesh(v, f)
        a = prtsub.bake(mesh, basis="sg:9", rays=64)
        self.assertEqual((a.lobes, a.order, a.channels), (9, 8, 1))  # relit through order 8 (sg_shading_order)
        c = np.array(a.transfer)
        self.assertEqual(c.shape, (len(a.vertices), 9))
        self.assertGreaterEqual(c.min(), 0.0)
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "a.glb")
            prtsub.save(a, path)
            b = prtsub.load(path)
        self.assertEqual(b.lobes, 9)
        np.testing.assert_allclose(np.array(b.transfer), c, rtol=1e-6, atol=1e-7)
        # Under constant light each lobe sees 4π e^{-λ} sinh(λ)/λ: a frame's pixels are albedo/π · Σ c_k of that.
        img = prtsub.render(b, prtsub.constant([1, 1, 1]), (40, 30), albedo=1.0)
        lam = math.log(2) / (1 - math.cos(math.sqrt(4 * math.pi / 9) / 2))
        lobe = 4 * math.pi * math.exp(-lam) * math.sinh(lam) / lam
        covered = img[..., 3] > 0
        self.assertGreater(covered.sum(), 0)
        self.assertLessEqual(img[..., 0][covered].max(), c.sum(axis=1).max() * lobe / math.pi * (1 + 1e-5))
        self.assertGreaterEqual(img[..., 0][covered].min(), 0.0)
        with self.assertRaisesRegex(ValueError, "--fit point"):
            prtsub.bake(mesh, basis="sg:9", fit="lsq")

if __name__ == "__main__":
    unittest.main()
