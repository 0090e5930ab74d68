//! Colliders and contacts: the signed distance and normal of every shape
//! (plane, ball, cuboid, capsule, closed and open triangle meshes), Coulomb
//! friction on an inclined plane (stick and slide), the drape scene's ball,
//! fast particles that must not tunnel through thin colliders, and typed
//! errors for bad colliders.

#![allow(clippy::unwrap_used)] // in test helpers, a panic is a test failure

use approx::assert_relative_eq;
use modelgap_cloth::{
    ClothError, ClothWorld, Collider, GridCloth, Method, Scene, Shape, SolverParams, scenes,
};
use nalgebra::{Isometry3, Vector3};

const G: f64 = 9.81;

/// Both solvers must handle contacts the same way.
const METHODS: [Method; 2] = [Method::GaussSeidel, Method::Newton];

fn solver(method: Method) -> SolverParams {
    SolverParams {
        method,
        max_iterations: 500,
        ..SolverParams::default()
    }
}

/// The eight corners and twelve outward (counter-clockwise) triangles of the
/// box `[-h, h]` centred at the origin.
fn box_mesh(h: Vector3<f64>) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let mut vertices = Vec::new();
    for i in 0..8 {
        let s = |bit: u32| if i & (1 << bit) != 0 { 1.0 } else { -1.0 };
        vertices.push(Vector3::new(s(0) * h.x, s(1) * h.y, s(2) * h.z));
    }
    // Vertex i has x from bit 0, y from bit 1, z from bit 2.
    let triangles = vec![
        [0, 4, 6],
        [0, 6, 2], // -x
        [1, 3, 7],
        [1, 7, 5], // +x
        [0, 1, 5],
        [0, 5, 4], // -y
        [2, 6, 7],
        [2, 7, 3], // +y
        [0, 2, 3],
        [0, 3, 1], // -z
        [4, 5, 7],
        [4, 7, 6], // +z
    ];
    (vertices, triangles)
}

/// An open square floor at height `y` (x, z in `[-half, half]`), front facing +y.
fn floor_mesh(y: f64, half: f64) -> Collider {
    let vertices = vec![
        Vector3::new(-half, y, -half),
        Vector3::new(half, y, -half),
        Vector3::new(half, y, half),
        Vector3::new(-half, y, half),
    ];
    // Counter-clockwise seen from +y.
    Collider::trimesh(vertices, vec![[0, 2, 1], [0, 3, 2]]).unwrap()
}

fn assert_sd(c: &Collider, x: [f64; 3], phi: f64, n: [f64; 3]) {
    let (got_phi, got_n) = c.signed_distance(&Vector3::from(x));
    // Exact geometry: only rounding separates the answers.
    assert_relative_eq!(got_phi, phi, epsilon = 1e-12);
    assert_relative_eq!(got_n, Vector3::from(n), epsilon = 1e-12);
}

#[test]
fn every_shape_gives_sign_and_normal() {
    let plane = Collider::plane(Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, 3.0, 0.0));
    assert_sd(&plane, [5.0, 1.5, -2.0], 0.5, [0.0, 1.0, 0.0]);
    assert_sd(&plane, [5.0, 0.75, -2.0], -0.25, [0.0, 1.0, 0.0]);

    let ball = Collider::ball(Vector3::new(1.0, 0.0, 0.0), 0.5);
    assert_sd(&ball, [1.0, 0.0, 2.0], 1.5, [0.0, 0.0, 1.0]);
    assert_sd(&ball, [0.8, 0.0, 0.0], -0.3, [-1.0, 0.0, 0.0]);

    // A box 2 x 1 x 0.5 m turned 90° about z: its local x runs along world y.
    let pose = Isometry3::new(
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
    );
    let cuboid = Collider::cuboid(Vector3::new(1.0, 0.5, 0.25), pose).unwrap();
    assert_sd(&cuboid, [0.0, 2.5, 0.0], 0.5, [0.0, 1.0, 0.0]);
    assert_sd(&cuboid, [0.0, 1.9, 0.0], -0.1, [0.0, 1.0, 0.0]);
    assert_sd(&cuboid, [0.4, 1.0, 0.0], -0.1, [1.0, 0.0, 0.0]);
    assert_sd(&cuboid, [0.0, 1.0, -0.2], -0.05, [0.0, 0.0, -1.0]);
    assert_sd(&cuboid, [0.0, 1.0, 0.25], 0.0, [0.0, 0.0, 1.0]);

    let capsule = Collider::capsule(
        Vector3::new(-1.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        0.5,
    )
    .unwrap();
    assert_sd(&capsule, [0.3, 0.2, 0.0], -0.3, [0.0, 1.0, 0.0]);
    assert_sd(&capsule, [0.3, 0.0, -2.0], 1.5, [0.0, 0.0, -1.0]);
    assert_sd(&capsule, [1.5, 0.0, 0.0], 0.0, [1.0, 0.0, 0.0]);
    assert_sd(&capsule, [2.0, 0.0, 0.0], 0.5, [1.0, 0.0, 0.0]);
    assert_sd(&capsule, [1.2, 0.0, 0.0], -0.3, [1.0, 0.0, 0.0]);

    let floor = floor_mesh(0.0, 1.0);
    let Shape::TriMesh(mesh) = &floor.shape else {
        panic!("a trimesh collider has a trimesh shape")
    };
    assert!(!mesh.is_closed());
    assert_sd(&floor, [0.2, 0.3, 0.1], 0.3, [0.0, 1.0, 0.0]);
    // Behind the front within the shell thickness (1 cm): penetrating.
    assert_sd(&floor, [0.2, -0.004, 0.1], -0.004, [0.0, 1.0, 0.0]);
    // Further behind: the back side, outside.
    assert_sd(&floor, [0.2, -0.3, 0.1], 0.3, [0.0, -1.0, 0.0]);
}

#[test]
fn closed_mesh_is_a_solid_matching_the_cuboid() {
    let h = Vector3::new(0.4, 0.2, 0.3);
    let pose = Isometry3::new(Vector3::new(0.1, -0.2, 0.3), Vector3::new(0.3, -0.5, 0.2));
    let (vertices, triangles) = box_mesh(h);
    let mesh = Collider::trimesh(vertices, triangles)
        .unwrap()
        .transformed(&pose);
    let Shape::TriMesh(m) = &mesh.shape else {
        panic!("a trimesh collider has a trimesh shape")
    };
    assert!(m.is_closed());
    let cuboid = Collider::cuboid(h, pose).unwrap();
    let mut state = 12345_u64;
    let mut inside = 0;
    for _ in 0..400 {
        let mut x = Vector3::zeros();
        for c in x.iter_mut() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            *c = ((state >> 11) as f64 / (1u64 << 53) as f64) * 1.6 - 0.8;
        }
        let (phi_box, n_box) = cuboid.signed_distance(&x);
        let (phi_mesh, n_mesh) = mesh.signed_distance(&x);
        // Same geometry through two parry shapes: rounding only.
        assert_relative_eq!(phi_mesh, phi_box, epsilon = 1e-9);
        if phi_box.abs() > 1e-6 {
            assert_relative_eq!(n_mesh, n_box, epsilon = 1e-6);
        }
        inside += usize::from(phi_box < 0.0);
    }
    assert!(inside > 10, "the sample reaches inside the box: {inside}");
}

#[test]
fn swept_distance_keeps_a_fast_particle_on_its_side() {
    // Each collider is thin or small next to a 2 m jump from y = 1 to y = -1.
    let start = Vector3::new(0.05, 1.0, 0.005);
    let end = Vector3::new(0.05, -1.0, 0.005);
    let (cube_v, cube_t) = box_mesh(Vector3::new(0.5, 0.001, 0.5));
    let colliders = [
        Collider::ball(Vector3::zeros(), 0.1),
        Collider::cuboid(Vector3::new(0.5, 0.001, 0.5), Isometry3::identity()).unwrap(),
        Collider::capsule(
            Vector3::new(-1.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            0.01,
        )
        .unwrap(),
        Collider::trimesh(cube_v, cube_t).unwrap(),
        floor_mesh(0.0, 0.5),
    ];
    for c in &colliders {
        let (phi_end, _) = c.signed_distance(&end);
        assert!(
            phi_end > 0.0,
            "{}: the end alone looks free",
            c.shape_name()
        );
        let (phi, n) = c.swept_distance(&start, &end);
        assert!(phi < -0.5, "{}: swept depth {phi}", c.shape_name());
        // Pushed out along the normal, the particle's path is clear.
        let pushed = end - phi * n;
        assert!(
            c.signed_distance(&pushed).0 >= -1e-9 && c.swept_distance(&start, &pushed).0 >= -1e-9,
            "{}: pushed to {pushed}",
            c.shape_name()
        );
        // A path that stays above touches nothing.
        let (phi_free, _) = c.swept_distance(&start, &Vector3::new(0.3, 0.5, 0.0));
        assert!(phi_free > 0.0, "{}", c.shape_name());
    }
}

#[test]
fn swept_distance_from_the_surface() {
    // Resting on a 2 mm plate (on its top face, or a rounding inside it) and
    // pushed 5 cm down in one step: held at the top face.
    let plate = Collider::cuboid(Vector3::new(0.5, 0.001, 0.5), Isometry3::identity()).unwrap();
    for y in [0.001, 0.001 - 1e-12] {
        let start = Vector3::new(0.1, y, 0.1);
        let end = Vector3::new(0.12, -0.05, 0.1);
        let (phi, n) = plate.swept_distance(&start, &end);
        assert_relative_eq!(phi, -0.051, epsilon = 1e-9);
        assert_relative_eq!(n, Vector3::y(), epsilon = 1e-12);
    }
    // Sliding over a ball from one surface point to another: the chord dips
    // under the surface, but the end is outside, so nothing pushes it.
    let ball = Collider::ball(Vector3::zeros(), 0.3);
    let on = |angle: f64| Vector3::new(0.3 * angle.sin(), 0.3 * angle.cos(), 0.0);
    let (phi, _) = ball.swept_distance(&(on(0.0) * (1.0 + 1e-12)), &(on(0.1) * (1.0 + 1e-12)));
    assert!(phi >= 0.0, "a slide over the ball is no collision: {phi}");
}

/// A 3 x 3 cloth (5 cm spacing) at rest `gap` m above the top of the
/// collider's surface at the origin, moving down at `speed` m/s.
fn falling_cloth(collider: Collider, top: f64, gap: f64, speed: f64, method: Method) -> ClothWorld {
    let mut world = ClothWorld::new(solver(method));
    let origin = Isometry3::translation(-0.05, top + gap, -0.05);
    let cloth = world
        .add_cloth(GridCloth::new(3, 3, 0.05).world_from_local(origin))
        .unwrap();
    world.add_collider(collider);
    for k in 0..9 {
        let p = world.particle(cloth, k).unwrap().index();
        world.particles_mut().velocities[p] = Vector3::new(0.0, -speed, 0.0);
    }
    world
}

#[test]
fn fast_cloth_does_not_tunnel_through_thin_colliders() {
    // 40 m/s over 10 ms is 0.4 m per step: one step would cross any of them.
    let thin = 0.002;
    let (cube_v, cube_t) = box_mesh(Vector3::new(0.5, thin / 2.0, 0.5));
    let cases = [
        (
            Collider::cuboid(Vector3::new(0.5, thin / 2.0, 0.5), Isometry3::identity()).unwrap(),
            thin / 2.0,
        ),
        (Collider::trimesh(cube_v, cube_t).unwrap(), thin / 2.0),
        (floor_mesh(0.0, 0.5), 0.0),
    ];
    for ((collider, top), method) in cases
        .into_iter()
        .flat_map(|c| METHODS.map(|m| (c.clone(), m)))
    {
        let name = format!("{} ({method:?})", collider.shape_name());
        let mut world = falling_cloth(collider.clone(), top, 0.1, 40.0, method);
        let mut touched = 0;
        for step in 0..20 {
            let r = world.step(0.01).unwrap();
            assert!(r.max_penetration <= 1e-3, "{name} step {step}: {r:?}");
            touched = touched.max(r.n_contacts);
            for x in &world.particles().positions {
                assert!(x.y > top - 1e-3, "{name} step {step}: tunnelled to {x}");
            }
        }
        assert!(touched > 0, "{name}: the cloth reached the collider");
    }
}

#[test]
fn cloth_rests_on_every_shape() {
    let (cube_v, cube_t) = box_mesh(Vector3::new(0.3, 0.1, 0.3));
    let cases = [
        (Collider::plane(Vector3::zeros(), Vector3::y()), 0.0),
        (Collider::ball(Vector3::new(0.0, -0.2, 0.0), 0.2), 0.0),
        (
            Collider::cuboid(
                Vector3::new(0.3, 0.1, 0.3),
                Isometry3::translation(0.0, -0.1, 0.0),
            )
            .unwrap(),
            0.0,
        ),
        (
            Collider::capsule(
                Vector3::new(-0.3, -0.05, 0.0),
                Vector3::new(0.3, -0.05, 0.0),
                0.05,
            )
            .unwrap(),
            0.0,
        ),
        (
            Collider::trimesh(cube_v, cube_t)
                .unwrap()
                .transformed(&Isometry3::translation(0.0, -0.1, 0.0)),
            0.0,
        ),
        (floor_mesh(0.0, 0.5), 0.0),
    ];
    for ((collider, top), method) in cases
        .into_iter()
        .flat_map(|c| METHODS.map(|m| (c.clone(), m)))
    {
        let name = format!("{} ({method:?})", collider.shape_name());
        let collider = collider.friction(0.5);
        let mut world = falling_cloth(collider.clone(), top, 0.05, 0.0, method);
        let mut touched = 0;
        for step in 0..60 {
            let r = world.step(0.01).unwrap();
            assert!(r.max_penetration <= 1e-3, "{name} step {step}: {r:?}");
            touched = touched.max(r.n_contacts);
            for x in &world.particles().positions {
                let phi = collider.signed_distance(x).0;
                assert!(phi >= -1e-3, "{name} step {step}: {x} is {phi} m inside");
            }
        }
        assert!(touched > 0, "{name}: the cloth reached the collider");
        // The centre particle came to rest on top (it started 5 cm above).
        let centre = world.particles().positions[4];
        let v = world.particles().velocities[4];
        assert!(
            centre.y > top - 1e-3 && centre.y < top + 0.01,
            "{name}: centre at {centre}"
        );
        assert!(v.norm() < 0.05, "{name}: centre still moving at {v}");
    }
}

/// A 3 x 3 cloth (2 cm spacing) lying on a plane inclined by `theta` rad with
/// friction `mu`, left alone for `seconds`; returns the displacement of its
/// centre down the slope (m) and its velocity along the slope (m/s).
fn slide_on_incline(theta: f64, mu: f64, seconds: f64, method: Method) -> (f64, f64) {
    // The plane through the origin rises towards −x: normal (sin θ, cos θ, 0),
    // downhill (cos θ, −sin θ, 0). The grid's local x runs downhill.
    let normal = Vector3::new(theta.sin(), theta.cos(), 0.0);
    let downhill = Vector3::new(theta.cos(), -theta.sin(), 0.0);
    let mut world = ClothWorld::new(solver(method));
    let pose = Isometry3::new(Vector3::zeros(), Vector3::new(0.0, 0.0, -theta));
    let cloth = world
        .add_cloth(GridCloth::new(3, 3, 0.02).world_from_local(pose))
        .unwrap();
    world.add_collider(Collider::plane(Vector3::zeros(), normal).friction(mu));
    let start = world.positions(cloth)[4];
    let dt = 0.01;
    let steps = (seconds / dt).round() as usize;
    for _ in 0..steps {
        let r = world.step(dt).unwrap();
        assert!(r.max_penetration <= 1e-9, "{r:?}");
        for x in world.positions(cloth) {
            assert!(x.dot(&normal) > -1e-9, "inside the plane: {x}");
        }
    }
    let moved = world.positions(cloth)[4] - start;
    let v = world.velocities(cloth)[4];
    (moved.dot(&downhill), v.dot(&downhill))
}

#[test]
fn cloth_sticks_when_friction_exceeds_the_slope() {
    let theta = 20_f64.to_radians(); // tan θ = 0.364
    for method in METHODS {
        let (moved, v) = slide_on_incline(theta, 0.5, 1.0, method);
        assert!(moved.abs() < 1e-3, "{method:?}: moved {moved} m in 1 s");
        assert!(v.abs() < 1e-3, "{method:?}: still moving at {v} m/s");
    }
}

#[test]
fn cloth_slides_with_coulomb_acceleration_below_the_slope() {
    let theta = 20_f64.to_radians();
    let mu = 0.2;
    let seconds = 1.0;
    let a = G * (theta.sin() - mu * theta.cos()); // 1.51 m/s²
    for method in METHODS {
        let (moved, v) = slide_on_incline(theta, mu, seconds, method);
        // Within 10 % of uniform acceleration from rest.
        assert_relative_eq!(moved, 0.5 * a * seconds * seconds, max_relative = 0.1);
        assert_relative_eq!(v, a * seconds, max_relative = 0.1);
        // Frictionless: g sin θ.
        let (moved, _) = slide_on_incline(theta, 0.0, seconds, method);
        assert_relative_eq!(moved, 0.5 * G * theta.sin(), max_relative = 0.1);
    }
}

#[test]
fn drape_never_penetrates_the_ball_by_more_than_a_millimetre() {
    // The drape scene on a 15 x 15 grid (same 1 m square) for its full 3 s.
    let scene = scenes::drape().resized(15, 15).unwrap();
    let Shape::Ball { center, radius } = scene.colliders[0].shape else {
        panic!("the drape scene's collider is a ball")
    };
    let (mut world, cloth) = scene.build().unwrap();
    *world.params_mut() = SolverParams {
        method: Method::GaussSeidel,
        max_iterations: 1000,
        ..scene.params.clone()
    };
    let mut touched = 0;
    for step in 0..scene.n_steps() {
        let r = world.step(scene.dt).unwrap();
        assert!(r.max_penetration <= 1e-3, "step {step}: {r:?}");
        touched = touched.max(r.n_contacts);
        for x in world.positions(cloth) {
            let depth = radius - (x - center).norm();
            assert!(
                depth <= 1e-3,
                "step {step}: {x} is {depth} m inside the ball"
            );
        }
    }
    assert!(touched > 0, "the cloth reached the ball");
    let top = world.positions(cloth)[7 * 15 + 7];
    assert!(
        top.y > center.y + radius - 1e-3 && top.y < center.y + radius + 0.02,
        "the centre rests on the ball: {top}"
    );
}

#[test]
fn bad_colliders_give_typed_errors() {
    let field_of = |e: ClothError| match e {
        ClothError::BadCollider { shape, field, .. } => format!("{shape}.{field}"),
        other => panic!("expected BadCollider, found {other}"),
    };
    let id = Isometry3::identity();
    let cuboid = |h: Vector3<f64>| Collider::cuboid(h, id).unwrap_err();
    assert_eq!(
        field_of(cuboid(Vector3::new(1.0, 0.0, 1.0))),
        "cuboid.half_extents"
    );
    assert_eq!(
        field_of(cuboid(Vector3::new(1.0, -1.0, 1.0))),
        "cuboid.half_extents"
    );
    assert_eq!(
        field_of(cuboid(Vector3::new(f64::NAN, 1.0, 1.0))),
        "cuboid.half_extents"
    );
    let nan_pose = Isometry3::translation(f64::NAN, 0.0, 0.0);
    assert_eq!(
        field_of(Collider::cuboid(Vector3::repeat(1.0), nan_pose).unwrap_err()),
        "cuboid.world_from_local.translation"
    );
    let (a, b) = (Vector3::zeros(), Vector3::x());
    assert_eq!(
        field_of(Collider::capsule(a, b, 0.0).unwrap_err()),
        "capsule.radius"
    );
    assert_eq!(
        field_of(Collider::capsule(a, b, f64::NAN).unwrap_err()),
        "capsule.radius"
    );
    assert_eq!(
        field_of(Collider::capsule(Vector3::repeat(f64::INFINITY), b, 1.0).unwrap_err()),
        "capsule.a"
    );
    let square = vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 1.0),
        Vector3::new(2.0, 0.0, 2.0),
    ];
    let mesh = |v: &[Vector3<f64>], t: Vec<[u32; 3]>| Collider::trimesh(v.to_vec(), t);
    assert_eq!(
        field_of(mesh(&square, vec![]).unwrap_err()),
        "trimesh.triangles"
    );
    let err = mesh(&square, vec![[0, 1, 2], [0, 2, 4]]).unwrap_err();
    assert!(err.to_string().contains("below 4"), "{err}");
    assert_eq!(field_of(err), "trimesh.triangles[1]");
    // A repeated vertex, then three points on a line.
    assert_eq!(
        field_of(mesh(&square, vec![[0, 1, 1]]).unwrap_err()),
        "trimesh.triangles[0]"
    );
    assert_eq!(
        field_of(mesh(&square, vec![[0, 1, 2], [0, 2, 3]]).unwrap_err()),
        "trimesh.triangles[1]"
    );
    let mut nan = square.clone();
    nan[2].y = f64::NAN;
    assert_eq!(
        field_of(mesh(&nan, vec![[0, 1, 2]]).unwrap_err()),
        "trimesh.vertices[2]"
    );
    assert_eq!(
        field_of(Collider::trimesh_with_shell(square.clone(), vec![[0, 1, 2]], 0.0).unwrap_err()),
        "trimesh.shell_thickness"
    );
    assert_eq!(
        field_of(Collider::ball(Vector3::zeros(), -1.0).check().unwrap_err()),
        "ball.radius"
    );
    assert_eq!(
        field_of(
            Collider::ball(Vector3::zeros(), 1.0)
                .friction(-0.1)
                .check()
                .unwrap_err()
        ),
        "ball.friction"
    );
    let obj = "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n";
    let from_obj = Collider::trimesh_from_obj(obj.as_bytes()).unwrap();
    assert_sd(&from_obj, [0.2, -0.005, 0.2], -0.005, [0.0, 1.0, 0.0]);
}

const SCENE_HEAD: &str = "name = 'shapes'\nduration = 1.0\ndt = 0.01\n\
                          [cloth]\nnx = 3\nnz = 3\nsize = 0.1\norigin = [0.0, 0.5, 0.0]\n";

#[test]
fn scene_files_hold_every_shape() {
    let text = format!(
        "{SCENE_HEAD}
[[colliders]]
shape = 'plane'
point = [0.0, -1.0, 0.0]
normal = [0.0, 2.0, 0.0]
[[colliders]]
shape = 'ball'
center = [0.0, 0.0, 0.0]
radius = 0.1
friction = 0.3
[[colliders]]
shape = 'cuboid'
center = [0.0, -0.5, 0.0]
half_extents = [1.0, 0.1, 1.0]
rotation = [0.0, 0.1, 0.0]
[[colliders]]
shape = 'capsule'
a = [0.0, -0.2, 0.0]
b = [1.0, -0.2, 0.0]
radius = 0.05
[[colliders]]
shape = 'trimesh'
vertices = [[0.0, -0.3, 0.0], [1.0, -0.3, 0.0], [1.0, -0.3, 1.0]]
triangles = [[0, 2, 1]]
translation = [0.0, 0.1, 0.0]
shell_thickness = 0.02
friction = 0.5
"
    );
    let scene = Scene::from_toml(&text, "shapes").unwrap();
    let names: Vec<&str> = scene.colliders.iter().map(Collider::shape_name).collect();
    assert_eq!(names, ["plane", "ball", "cuboid", "capsule", "trimesh"]);
    assert_relative_eq!(scene.colliders[4].friction, 0.5);
    // The trimesh was moved up by 0.1 m: its front is at y = -0.2.
    assert_sd(
        &scene.colliders[4],
        [0.5, -0.21, 0.2],
        -0.01,
        [0.0, 1.0, 0.0],
    );
    // Written and read back, the colliders are the same.
    let again = Scene::from_toml(&scene.to_toml().unwrap(), "again").unwrap();
    for (a, b) in scene.colliders.iter().zip(&again.colliders) {
        for x in [[0.3, -0.25, 0.1], [0.0, 0.05, 0.0], [0.9, -0.45, -0.2]] {
            let x = Vector3::from(x);
            assert_relative_eq!(
                a.signed_distance(&x).0,
                b.signed_distance(&x).0,
                epsilon = 1e-12
            );
        }
    }
    let (mut world, _) = scene.build().unwrap();
    world.step(0.01).unwrap();
}

#[test]
fn scene_collider_errors_name_index_and_field() {
    let cases = [
        (
            "shape = 'ball'\ncenter = [0.0, 0.0, 0.0]\nradius = 0.0",
            "colliders[1]: ball collider: `radius`",
        ),
        (
            "shape = 'plane'\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]",
            "colliders[1]: plane collider: `normal`",
        ),
        (
            "shape = 'cuboid'\ncenter = [0.0, 0.0, 0.0]\nhalf_extents = [1.0, -1.0, 1.0]",
            "colliders[1]: cuboid collider: `half_extents`",
        ),
        (
            "shape = 'capsule'\na = [0.0, 0.0, 0.0]\nb = [1.0, 0.0, 0.0]\nradius = -2.0",
            "colliders[1]: capsule collider: `radius`",
        ),
        (
            "shape = 'trimesh'\nvertices = [[0.0, 0.0, 0.0]]\ntriangles = [[0, 1, 2]]",
            "colliders[1]: trimesh collider: `triangles[0]`",
        ),
        (
            "shape = 'ball'\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nfriction = -1.0",
            "colliders[1]: ball collider: `friction`",
        ),
    ];
    for (collider, expected) in cases {
        let text = format!(
            "{SCENE_HEAD}[[colliders]]\nshape = 'ball'\ncenter = [0.0, 0.0, 0.0]\nradius = 0.1\n\
             [[colliders]]\n{collider}\n"
        );
        let err = Scene::from_toml(&text, "bad").unwrap_err();
        assert!(matches!(err, ClothError::Scene { .. }), "{err:?}");
        assert!(err.to_string().contains(expected), "{err}");
    }
    let text = format!("{SCENE_HEAD}[[colliders]]\nshape = 'cone'\nradius = 1.0\n");
    let err = Scene::from_toml(&text, "bad").unwrap_err();
    assert!(err.to_string().contains("cone"), "{err}");
}

#[test]
fn scene_trimesh_reads_an_obj_file_next_to_the_scene() {
    let dir = std::env::temp_dir().join(format!("modelgap-contact-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A floor at y = -0.2, front facing +y.
    let obj = "v -1 -0.2 -1\nv 1 -0.2 -1\nv 1 -0.2 1\nv -1 -0.2 1\nf 1 3 2\nf 1 4 3\n";
    std::fs::write(dir.join("floor.obj"), obj).unwrap();
    let scene_text = format!(
        "{SCENE_HEAD}[[colliders]]\nshape = 'trimesh'\nobj = 'floor.obj'\nfriction = 0.4\n"
    );
    let scene_path = dir.join("floor.toml");
    std::fs::write(&scene_path, &scene_text).unwrap();
    let scene = Scene::from_path(&scene_path).unwrap();
    assert_sd(
        &scene.colliders[0],
        [0.3, -0.205, 0.1],
        -0.005,
        [0.0, 1.0, 0.0],
    );
    // Both an OBJ and inline triangles: which one is meant?
    let both = scene_text.replace("obj = ", "triangles = [[0, 1, 2]]\nobj = ");
    std::fs::write(&scene_path, both).unwrap();
    let err = Scene::from_path(&scene_path).unwrap_err();
    assert!(
        err.to_string()
            .contains("colliders[0]: a trimesh takes either"),
        "{err}"
    );
    // A missing file names the collider and the file.
    std::fs::remove_file(dir.join("floor.obj")).unwrap();
    std::fs::write(&scene_path, &scene_text).unwrap();
    let err = Scene::from_path(&scene_path).unwrap_err().to_string();
    assert!(
        err.contains("colliders[0]: cannot read") && err.contains("floor.obj"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
