"""The cloth simulator from Python: meshes, worlds, colliders, pins, scenes, markers, errors,
numpy in and out, the GIL released while stepping."""

from __future__ import annotations

import _thread
import pickle
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from modelgap import DataError, ModelgapError
from modelgap import cloth
from modelgap.cloth import (
    ClothMesh,
    ClothWorld,
    Collider,
    MarkerRecording,
    Scene,
    SolverParams,
    StepReport,
)

G = 9.81

# A unit square of two triangles, in the x-z plane.
SQUARE = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
SQUARE_TRIANGLES = np.array([[0, 1, 2], [0, 2, 3]])


def hanging(n: int = 10, **params) -> tuple[ClothWorld, int]:
    """An n x n grid, 5 cm apart, hanging from vertex 0."""
    world = ClothWorld(SolverParams(**params))
    return world, world.add_cloth(ClothMesh.grid(n, n, 0.05, pins=[0]))


def test_grid_is_the_papers_mesh():
    mesh = ClothMesh.grid(30, 30, 1.0 / 29.0)
    assert (mesh.n_vertices, mesh.n_edges) == (900, 1740)
    assert mesh.triangles.shape == (2 * 29 * 29, 3) and mesh.triangles.dtype == np.int64
    more = ClothMesh.grid(3, 3, 1.0, shear=True, bend=True)
    assert more.n_edges == 12 + 8 + 6
    placed = ClothMesh.grid(2, 2, 1.0, origin=(1.0, 2.0, 3.0), pins=[3, 0])
    np.testing.assert_array_equal(placed.vertices[3], [2.0, 2.0, 4.0])
    assert placed.pinned == [0, 3]
    assert "vertices=900 edges=1740" in repr(mesh)


def test_mesh_from_numpy_arrays_and_strided_input():
    mesh = ClothMesh(SQUARE, SQUARE_TRIANGLES, particle_mass=0.01, pins=[0])
    np.testing.assert_array_equal(mesh.edges, [[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]])
    np.testing.assert_array_equal(mesh.masses, [0.01] * 4)
    assert mesh.pinned == [0]
    # Every other column of a wider array, triangles in Fortran order, int32.
    wide = np.zeros((4, 6))
    wide[:, ::2] = SQUARE
    fortran = np.asfortranarray(SQUARE_TRIANGLES.astype(np.int32))
    strided = ClothMesh(wide[:, ::2], fortran, particle_mass=0.01, pins=np.array([0]))
    np.testing.assert_array_equal(strided.vertices, mesh.vertices)
    np.testing.assert_array_equal(strided.edges, mesh.edges)
    # Reversed rows of a reversed array: negative strides.
    back = ClothMesh(SQUARE[::-1][::-1], SQUARE_TRIANGLES[::-1][::-1])
    np.testing.assert_array_equal(back.vertices, SQUARE)


def test_obj_meshes(tmp_path: Path):
    text = "# a square\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3 4\n"
    mesh = ClothMesh.from_obj(text, pins=[0])
    assert (mesh.n_vertices, mesh.n_edges, len(mesh.triangles)) == (4, 5, 2)
    path = tmp_path / "square.obj"
    path.write_text(text)
    assert ClothMesh.load_obj(path).n_edges == 5
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0\n")
    with pytest.raises(DataError, match=r"OBJ line 2: expected 3 coordinates.*bad\.obj"):
        ClothMesh.load_obj(bad)
    with pytest.raises(DataError, match="cannot read .*missing.obj"):
        ClothMesh.load_obj(tmp_path / "missing.obj")


def test_bad_meshes_raise_value_errors_with_the_rust_message():
    with pytest.raises(DataError, match="a grid cloth needs at least 2 x 2 vertices, found 1 x 3"):
        ClothMesh.grid(1, 3, 0.1)
    with pytest.raises(DataError, match="parameter 'spacing' must be positive and finite, found 0"):
        ClothMesh.grid(3, 3, 0.0)
    with pytest.raises(DataError, match="vertex 7 is out of range: the mesh has 4 vertices"):
        ClothMesh(SQUARE, [[0, 1, 7]])
    with pytest.raises(DataError, match="edge 0-1 has zero rest length"):
        ClothMesh(np.zeros((3, 3)), [[0, 1, 2]])
    with pytest.raises(DataError, match=r"vertices must be \(n, 3\), found shape \[4, 2\]"):
        ClothMesh(SQUARE[:, :2], SQUARE_TRIANGLES)
    with pytest.raises(DataError, match="triangles must hold integers"):
        ClothMesh(SQUARE, SQUARE_TRIANGLES.astype(float))
    with pytest.raises(DataError, match=r"triangles must be \(m, 3\)"):
        ClothMesh(SQUARE, [[0, 1], [1, 2]])
    with pytest.raises(DataError, match="pins must be non-negative vertex indices.*found -1"):
        ClothMesh(SQUARE, SQUARE_TRIANGLES, pins=[-1])
    with pytest.raises(DataError, match="particle 2 has a non-finite position"):
        ClothMesh(np.where(np.arange(12).reshape(4, 3) == 7, np.nan, SQUARE), SQUARE_TRIANGLES)
    with pytest.raises(DataError) as e:
        ClothMesh.grid(2, 2, 1.0, pins=[4])
    assert isinstance(e.value, ValueError) and isinstance(e.value, ModelgapError)
    mesh = ClothMesh(SQUARE, SQUARE_TRIANGLES, pins=[0])
    with pytest.raises(DataError, match="vertex 4 is out of range"):
        mesh.pin(4)
    assert mesh.pinned == [0]  # a failed pin leaves the mesh as it was


def test_neighbouring_pins_are_allowed_and_their_edge_is_not_a_constraint():
    mesh = ClothMesh.grid(3, 3, 0.1, pins=[0, 1, 2])
    assert mesh.pinned == [0, 1, 2]
    world = ClothWorld()
    world.add_cloth(mesh)
    assert world.n_constraints == mesh.n_edges - 2
    assert world.step(dt=0.01).converged


def test_a_hanging_cloth_holds_its_constraints():
    world, c = hanging(10)
    report = world.step(20, dt=0.01)
    assert isinstance(report, StepReport)
    assert report.steps == 20 and report.converged and report.iterations >= 20
    assert report.max_stretch <= 1e-4
    assert world.max_stretch(c) <= 1e-4
    assert world.time == pytest.approx(0.2)
    x = world.positions(c)
    assert x.shape == (100, 3) and x.dtype == np.float64
    np.testing.assert_array_equal(x[0], [0.0, 0.0, 0.0])  # the pin
    assert x[:, 1].min() < -0.05  # the rest fell
    assert world.inv_masses(c)[0] == 0.0 and world.inv_masses(c)[1] == pytest.approx(1000.0)
    assert "converged=True" in repr(report) and "ClothWorld cloths=1" in repr(world)


def test_arrays_out_are_fresh_copies():
    world, c = hanging(4)
    x = world.positions(c)
    x[:] = 7.0
    assert world.positions(c)[0, 0] == 0.0
    v = world.velocities(c)
    world.step(1, dt=0.01)
    assert np.all(v == 0.0)  # the old array did not follow the step


def test_free_fall_keeps_momentum_exact():
    # No pins, no colliders: internal impulses cancel pair by pair, so the cloth's momentum
    # is that of free fall, M g t (to rounding).
    world = ClothWorld()
    c = world.add_cloth(ClothMesh.grid(6, 6, 0.1, particle_mass=0.002))
    world.step(30, dt=0.01)
    mass = 36 * 0.002
    np.testing.assert_allclose(world.momentum(), [0.0, -mass * G * 0.3, 0.0], atol=1e-12)
    np.testing.assert_allclose(world.velocities(c)[:, 1], -G * 0.3, rtol=1e-9)


def test_newton_and_gauss_seidel_agree():
    gs, c = hanging(8, method="gauss-seidel", max_iterations=10_000)
    newton, _ = hanging(8, stretch_tolerance=1e-8)
    gs.params = gs.params.replace(stretch_tolerance=1e-8)
    assert gs.params.stretch_tolerance == 1e-8
    assert newton.params.method == "newton", "Newton is the default"
    r1 = gs.step(10, dt=0.01)
    r2 = newton.step(10, dt=0.01)
    assert r1.converged and r2.converged and r2.factorizations >= 1
    assert max(r1.max_stretch, r2.max_stretch) <= 1e-8
    # Newton solves all constraints at once: a handful of solves per step, not sweeps.
    assert r2.iterations < r1.iterations / 5
    # Both hold every constraint, but reach different (equally valid) impulse splits, so
    # the two cloths part by a fraction of a millimetre in 0.1 s (0.3 mm when written).
    np.testing.assert_allclose(gs.positions(c), newton.positions(c), atol=2e-3)


def test_floor_plane_and_ball_colliders():
    world = ClothWorld()
    c = world.add_cloth(ClothMesh.grid(6, 6, 0.05, origin=(0.0, 0.02, 0.0)))
    floor = Collider.plane((0.0, 0.0, 0.0), (0.0, 2.0, 0.0), friction=0.5)
    assert world.add_collider(floor) == 0
    assert floor.geometry == {"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}
    report = world.step(40, dt=0.01)
    assert report.n_contacts == 36
    assert world.positions(c)[:, 1].min() >= -1e-4  # contact tolerance
    ball = Collider.ball([0.1, -0.2, 0.1], 0.1)
    assert ball.shape == "ball" and ball.signed_distance((0.1, -0.2, 0.1)) == -0.1
    assert world.colliders == [floor] and "plane" in repr(floor)


def test_cuboid_capsule_and_trimesh_colliders():
    # A cloth dropped on a table (a box), a rail (a capsule) and a floor (an open mesh).
    table = Collider.cuboid((0.2, 0.05, 0.2), center=(0.1, -0.15, 0.1), friction=0.3)
    assert table.signed_distance((0.1, -0.1, 0.1)) == pytest.approx(0.0, abs=1e-12)
    assert table.geometry["half_extents"] == [0.2, 0.05, 0.2]
    turned = Collider.cuboid((0.1, 0.05, 0.1), rotation=(0.0, np.pi / 2, 0.0))
    np.testing.assert_allclose(turned.geometry["rotation"], [0.0, np.pi / 2, 0.0], atol=1e-12)
    rail = Collider.capsule((0.0, -0.3, 0.0), (1.0, -0.3, 0.0), 0.02)
    assert rail.signed_distance((0.5, -0.3, 0.0)) == pytest.approx(-0.02)
    floor = Collider.trimesh(
        [[-1.0, -0.5, -1.0], [1.0, -0.5, -1.0], [1.0, -0.5, 1.0], [-1.0, -0.5, 1.0]],
        [[0, 2, 1], [0, 3, 2]],
    )
    assert floor.shape == "trimesh" and not floor.geometry["closed"]
    assert floor.signed_distance((0.0, -0.4, 0.0)) == pytest.approx(0.1)
    world = ClothWorld()
    c = world.add_cloth(ClothMesh.grid(5, 5, 0.05))
    for collider in (table, rail, floor):
        world.add_collider(collider)
    report = world.step(40, dt=0.01)
    assert report.n_contacts > 0
    x = world.positions(c)
    assert x[:, 1].min() > -0.1 - 1e-3  # resting on the table top (y = -0.1)
    assert [k.shape for k in world.colliders] == ["cuboid", "capsule", "trimesh"]
    with pytest.raises(DataError, match=r"cuboid collider: `half_extents` must be positive"):
        Collider.cuboid((0.1, 0.0, 0.1))
    with pytest.raises(DataError, match=r"trimesh collider: `triangles\[0\]`"):
        Collider.trimesh(np.zeros((3, 3)), [[0, 1, 2]])
    with pytest.raises(DataError, match="capsule collider: `radius` must be positive"):
        Collider.capsule((0, 0, 0), (1, 0, 0), 0.0)


def test_bad_colliders_and_params():
    with pytest.raises(
        DataError, match="ball collider: `radius` must be positive and finite, found -1"
    ):
        Collider.ball((0, 0, 0), -1.0)
    with pytest.raises(DataError, match="plane collider: `normal` must not be zero"):
        Collider.plane((0, 0, 0), (0, 0, 0))
    with pytest.raises(DataError, match=r"center must be three numbers \(x, y, z\)"):
        Collider.ball((0, 0), 1.0)
    with pytest.raises(
        DataError, match="ball collider: `friction` must be non-negative and finite, found -0.1"
    ):
        Collider.ball((0, 0, 0), 1.0, friction=-0.1)
    with pytest.raises(DataError, match='method must be "newton", "gauss-seidel" or "strips", found "cg"'):
        SolverParams(method="cg")
    with pytest.raises(DataError, match="stretch_tolerance must be positive"):
        SolverParams(stretch_tolerance=0.0)
    with pytest.raises(DataError, match="SolverParams has no parameter `tol`"):
        SolverParams().replace(tol=1.0)
    world, c = hanging(4)
    with pytest.raises(DataError, match="time step must be positive and finite, found 0 s"):
        world.step(1, dt=0.0)
    with pytest.raises(DataError, match=r"unknown cloth id 3 \(the world has 1 cloths\)"):
        world.positions(3)


def test_set_state_from_strided_arrays_and_bad_state():
    world, c = hanging(4)
    x = world.positions(c)
    wide = np.zeros((16, 6))
    wide[:, ::2] = x + [0.0, 0.0, 0.01]
    world.set_positions(wide[:, ::2], c)
    np.testing.assert_array_equal(world.positions(c), x + [0.0, 0.0, 0.01])
    world.set_velocities(np.ones((3, 16)).T, c)
    np.testing.assert_array_equal(world.velocities(c), np.ones((16, 3)))
    with pytest.raises(DataError, match=r"positions must be \(n, 3\) = \(16, 3\).*found \(15, 3\)"):
        world.set_positions(x[:15], c)
    bad = x.copy()
    bad[3, 1] = np.inf
    with pytest.raises(
        DataError, match=r"particle 3 has a non-finite position: \[0\.15\d*, inf, 0\]"
    ):
        world.set_positions(bad, c)


def test_kinematic_pin_follows_its_path():
    world, c = hanging(5)
    world.add_kinematic_pin(c, 0, [0.0, 1.0], [[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    assert world.n_kinematic_pins == 1
    world.step(50, dt=0.01)
    assert world.positions(c)[0, 0] == pytest.approx(0.1, abs=1e-12)
    with pytest.raises(DataError, match="vertex 3 is not pinned"):
        world.add_kinematic_pin(c, 3, [0.0], [[0.0, 0.0, 0.0]])
    with pytest.raises(DataError, match="pin path point 1: expected time after 0 s"):
        world.add_kinematic_pin(c, 0, [0.0, 0.0], np.zeros((2, 3)))


def test_record_markers_and_follow_them():
    world, c = hanging(5)
    rec = world.record(10, dt=0.01, ids=[0, 24], every=4)
    assert rec.n_frames == 1 + 2 + 1 and rec.n_markers == 2  # start, 4, 8, and the last (10)
    np.testing.assert_allclose(rec.t, [0.0, 0.04, 0.08, 0.1], atol=1e-12)
    np.testing.assert_array_equal(rec.ids, [0, 24])
    np.testing.assert_array_equal(rec.track(24)[-1], world.positions(c)[24])
    with pytest.raises(DataError, match="marker 5 is not recorded; recorded ids: 0, 24"):
        rec.track(5)
    with pytest.raises(DataError, match="vertex 25 is out of range"):
        world.record(1, ids=[25])
    # A second world's pin follows the first world's recorded pin (which stayed put) ...
    other, c2 = hanging(5)
    moved = MarkerRecording([0.0, 1.0], [0], [[[0.0, 0.0, 0.0]], [[0.0, 0.5, 0.0]]])
    assert other.follow_markers(c2, moved) == 1
    other.step(50, dt=0.01)
    assert other.positions(c2)[0, 1] == pytest.approx(0.25, abs=1e-12)


def test_marker_recordings_files_numpy_and_errors(tmp_path: Path):
    t = np.array([0.0, 0.01, 0.02])
    x = np.arange(18, dtype=float).reshape(3, 2, 3) / 10
    rec = MarkerRecording(t, [4, 9], x)
    t2, ids, x2 = rec.to_numpy()
    np.testing.assert_array_equal(x2, x)
    assert ids.dtype == np.int64 and list(ids) == [4, 9] and len(rec) == 3
    for ext in ("csv", "mcap"):
        path = tmp_path / f"m.{ext}"
        rec.save(path)
        assert MarkerRecording.load(path) == rec
    assert pickle.loads(pickle.dumps(rec)) == rec
    strided = np.zeros((3, 2, 6))
    strided[:, :, ::2] = x
    assert MarkerRecording(t, np.array([4, 9]), strided[:, :, ::2]) == rec
    with pytest.raises(DataError, match="marker time is not strictly increasing"):
        MarkerRecording([0.0, 0.02, 0.01], [4, 9], x)
    with pytest.raises(
        DataError, match=r"positions must be \(n_frames, n_markers, 3\) = \(3, 1, 3\)"
    ):
        MarkerRecording(t, [4], x)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,id,x,y,z\n0,0,0,0,0\n0.1,0,abc,0,0\n")
    with pytest.raises(DataError, match=r"`x` at line 3, found `abc` in .*bad\.csv"):
        MarkerRecording.load(bad)
    with pytest.raises(DataError, match="unknown file extension `txt`"):
        rec.save(tmp_path / "m.txt")


def test_reference_scenes_and_scene_files(tmp_path: Path):
    assert cloth.scenes() == ["corner", "two-corners", "drape"]
    corner = cloth.scene("corner")
    assert isinstance(corner, Scene)
    assert corner.grid == (30, 30) and corner.pins == [0] and corner.dt == 0.01
    assert cloth.scene("two-corners").pins == [0, 29]
    drape = cloth.scene("drape")
    assert drape.colliders[0].shape == "ball" and drape.colliders[0].friction == 0.3
    with pytest.raises(DataError, match="nope"):
        cloth.scene("nope")
    small = corner.resized(6, 6)
    assert small.grid == (6, 6) and small.spacing == pytest.approx(0.2)
    text = """name = "mine"
duration = 0.1
dt = 0.01
[cloth]
nx = 4
nz = 4
size = 0.3
pins = [0, 3]
[[colliders]]
shape = "plane"
point = [0.0, -0.5, 0.0]
normal = [0.0, 1.0, 0.0]
"""
    path = tmp_path / "mine.toml"
    path.write_text(text)
    mine = Scene.load(path)
    assert (mine.name, mine.pins, mine.n_steps) == ("mine", [0, 3], 10)
    with pytest.raises(DataError, match=r"(?s)scene '.*bad\.toml'.*line 4.*unknown field `colour`"):
        bad = tmp_path / "bad.toml"
        bad.write_text(text.replace("dt = 0.01", "dt = 0.01\ncolour = 1"))
        Scene.load(bad)
    with pytest.raises(DataError, match="dt must be positive and finite, found -0.01"):
        Scene.from_toml(text.replace("dt = 0.01", "dt = -0.01"))


def test_scene_run_records_frames_and_writes_files(tmp_path: Path):
    scene = cloth.scene("corner").resized(6, 6)
    run = scene.run(duration=0.2)
    assert run.frames.shape == (21, 36, 3)
    assert run.markers is not None and run.markers.n_frames == 21
    stats = run.stats
    assert stats["steps"] == 20 and stats["unconverged_steps"] == 0
    assert stats["max_stretch"] <= 1e-4
    assert run.triangles.shape == (50, 3) and run.edges.shape == (60, 2)
    # The run is the world stepped by hand.
    world = scene.world()
    world.step(20, dt=scene.dt)
    np.testing.assert_array_equal(run.frames[-1], world.positions())
    some = scene.run(duration=0.1, rate=50.0, markers=[0, 35])
    assert some.markers is not None and list(some.markers.ids) == [0, 35]
    assert some.markers.n_frames == 6
    assert scene.run(duration=0.05, markers="none").markers is None
    run.save(tmp_path / "run.mcap")
    assert MarkerRecording.load(tmp_path / "run.mcap") == run.markers
    run.save(tmp_path / "run.csv")
    assert MarkerRecording.load(tmp_path / "run.csv") == run.markers
    with pytest.raises(DataError, match="vertex 36 is out of range"):
        scene.run(duration=0.05, markers=[36])


def test_pickling_cloth_values():
    params = SolverParams(method="newton", gravity=(0.0, -1.62, 0.0))
    assert pickle.loads(pickle.dumps(params)) == params
    mesh = ClothMesh.grid(4, 3, 0.1, pins=[0], shear=True)
    back = pickle.loads(pickle.dumps(mesh))
    np.testing.assert_array_equal(back.edges, mesh.edges)
    np.testing.assert_array_equal(back.vertices, mesh.vertices)
    assert back.pinned == [0] and type(back) is ClothMesh
    scene = cloth.scene("drape").resized(5, 5).with_params(params)
    back_scene = pickle.loads(pickle.dumps(scene))
    assert back_scene.to_toml() == scene.to_toml() and back_scene.params == params
    assert back_scene.colliders == scene.colliders
    world, _ = hanging(4)
    report = world.step(3, dt=0.01)
    again = pickle.loads(pickle.dumps(report))
    assert (again.steps, again.iterations, again.max_stretch) == (
        3,
        report.iterations,
        report.max_stretch,
    )


def test_marker_errors_match_by_id():
    t = [0.0, 0.1]
    a = MarkerRecording(t, [1, 2], np.zeros((2, 2, 3)))
    shifted = np.zeros((2, 3, 3))
    shifted[:, 0, 0] = [0.3, 0.4]  # id 2: 0.3 m then 0.4 m away
    b = MarkerRecording(t, [2, 1, 7], shifted)
    ids, rms = cloth.marker_errors(a, b)
    assert list(ids) == [2, 1]
    np.testing.assert_allclose(rms, [np.sqrt((0.09 + 0.16) / 2), 0.0])
    with pytest.raises(ValueError, match="share their frame times"):
        cloth.marker_errors(a, MarkerRecording([0.0], [1], np.zeros((1, 1, 3))))


def test_progress_is_reported_and_an_exception_stops_the_step():
    world, _ = hanging(4)
    seen: list[tuple[int, int]] = []
    world.step(30, dt=0.01, progress=lambda done, total: seen.append((done, total)))
    assert seen and seen[-1] == (30, 30)

    def boom(done: int, total: int) -> None:
        raise RuntimeError("stop here")

    big, _ = hanging(20, stretch_tolerance=1e-9, max_iterations=200)
    with pytest.raises(RuntimeError, match="stop here"):
        big.step(100_000, dt=0.001, progress=boom)
    assert 0.0 < big.time < 100.0  # the steps done stay done


def test_step_releases_the_gil():
    # A long step on a worker thread; the main thread must keep counting meanwhile.
    world, _ = hanging(20, stretch_tolerance=1e-9, max_iterations=400)
    done = threading.Event()

    def work() -> None:
        # Long enough to tell on a fast machine (150 steps took 44 ms in a release build).
        world.step(1000, dt=0.001)
        done.set()

    worker = threading.Thread(target=work)
    start = time.perf_counter()
    worker.start()
    counts = 0
    while not done.is_set():
        counts += 1
        time.sleep(0.001)
    worker.join()
    elapsed = time.perf_counter() - start
    assert elapsed > 0.05, "the stepping was too short to tell"
    # Holding the GIL would freeze the loop: expect at least an eighth of the ideal count.
    assert counts > 0.125 * elapsed / 0.001


def test_ctrl_c_stops_a_long_step():
    world, _ = hanging(20, stretch_tolerance=1e-9, max_iterations=200)
    timer = threading.Timer(0.2, _thread.interrupt_main)
    timer.start()
    try:
        # Long enough that only Ctrl-C ends it in time, short enough that a lost interrupt
        # fails the test (pytest.raises) instead of hanging the suite: seen once, under a
        # cold first run, not reproduced in 9 runs since.
        with pytest.raises(KeyboardInterrupt):
            world.step(30_000, dt=0.001)
    finally:
        timer.cancel()
    assert 0.0 < world.time < 1000.0


def test_an_unreachable_tolerance_stagnates_once_and_says_the_level():
    # A 12 x 6 cloth held by every other vertex of its top row, inextensible: the straight
    # row between two pins cannot hold its load to 1e-9.
    world = ClothWorld(SolverParams(stretch_tolerance=1e-9, max_iterations=1000))
    world.add_cloth(ClothMesh.grid(12, 6, 0.05, pins=list(range(0, 12, 2))))
    report = world.step(30, dt=0.01)
    assert report.stagnated
    assert report.relaxed_tolerance is not None and report.relaxed_tolerance > 1e-9
    assert report.iterations < 30 * 1000 / 10
    assert world.stagnation is not None and "cannot be reached" in world.stagnation
    assert pickle.loads(pickle.dumps(report)).relaxed_tolerance == report.relaxed_tolerance


def test_a_scene_asks_for_the_second_order_step_and_a_report_says_when_it_fell_back():
    text = cloth.scene("corner").resized(8, 8).to_toml()
    text = text.replace("gravity =", 'integrator = "bdf2"\ngravity =', 1)
    scene = Scene.from_toml(text)
    assert 'integrator = "bdf2"' in scene.to_toml()
    report = scene.world().step(100, dt=0.01)
    assert report.converged
    assert isinstance(report.first_order, bool)
    assert pickle.loads(pickle.dumps(report)).first_order == report.first_order
    with pytest.raises(DataError, match=r'integrator.*"rk4"'):
        Scene.from_toml(text.replace('"bdf2"', '"rk4"'))
    assert scene.params.integrator == "bdf2"
    params = SolverParams(integrator="bdf2")
    assert params.kwargs()["integrator"] == "bdf2"
    assert pickle.loads(pickle.dumps(params)) == params != SolverParams()
    with pytest.raises(DataError, match='integrator must be "impulse" or "bdf2", found "rk4"'):
        SolverParams(integrator="rk4")
