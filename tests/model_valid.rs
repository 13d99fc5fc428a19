//! The model's validation pass (`poser::model::valid`): a model built in Rust, not by the
//! front end, is checked before any back end compiles or renders it. Each rule is planted
//! here and expected to be caught, named by its path in the model; every shipped scene passes
//! (`scenarios::every_example_scene_validates`, `compile_out`).

use crate::support::model::{self as m, Sensor};
use glam::{DMat3, DVec3};
use poser::backend::{Backend, RenderOptions};
use poser::model::*;

fn built() -> Model {
    let sensor = Sensor {
        width: 32,
        height: 24,
        fx: 30.0,
        pitch: 5e-6,
        cx: 16.0,
        cy: 12.0,
    };
    let cam = m::camera("cam", sensor, m::flat_port(0.02, 0.01));
    let water = m::water(
        [1.34; 3],
        [0.3, 0.06, 0.02],
        [0.05; 3],
        Phase::HenyeyGreenstein { g: 0.9 },
    );
    let mut model = m::model(
        "valid",
        cam,
        Some(water),
        m::nadir(DVec3::new(0.0, 0.0, -8.0)),
    );
    model.objects.push(m::plane("bed", -10.0, 4.0, [0.3; 3]));
    model
        .lights
        .push(m::rig_spot(DVec3::new(0.1, 0.0, 0.0), 5.0));
    model
}

fn paths(model: &Model) -> Vec<String> {
    match model.validate() {
        Ok(()) => vec![],
        Err(e) => e.problems.into_iter().map(|p| p.path).collect(),
    }
}

#[test]
fn a_model_built_in_rust_is_valid() {
    assert_eq!(paths(&built()), Vec::<String>::new());
}

#[test]
fn every_broken_rule_is_found_and_named_by_its_path() {
    let mut model = built();
    model.cameras[0].fx = f64::NAN;
    if let Port::Flat { thickness, .. } = &mut model.cameras[0].port {
        *thickness = 0.0;
    }
    model.poses[0].world_from_rig.rotation = DMat3::from_diagonal(DVec3::new(1.0, 1.0, 2.0));
    model.water.as_mut().unwrap().scattering[2] = -0.01;
    if let LightKind::Spot { half_angle, .. } = &mut model.lights[0].kind {
        *half_angle = 0.0;
    }
    model.objects[0].scale.y = 0.0;
    model.render.samples = 0;
    let got = paths(&model);
    assert_eq!(
        got,
        [
            "cameras[0].fx",
            "cameras[0].port.thickness",
            "water.scattering",
            "lights[0].half_angle",
            "objects[0].scale.y",
            "poses[0].world_from_rig.rotation",
            "render.samples",
        ]
    );
    // A mirror is orthonormal but not a rotation.
    let mut model = built();
    model.objects[0].pose.rotation = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
    assert_eq!(paths(&model), ["objects[0].pose.rotation"]);
    // A port's normal must be a unit vector, a glass index at least 1.
    let mut model = built();
    if let Port::Flat { normal, glass, .. } = &mut model.cameras[0].port {
        *normal = DVec3::new(0.0, 0.0, 2.0);
        glass.ior[0] = 0.9;
    }
    assert_eq!(
        paths(&model),
        ["cameras[0].port.normal", "cameras[0].port.glass.ior"]
    );
    // A glass object is a box, a uniformly scaled sphere or a round cylinder.
    let glass = Some(Glass {
        name: "N-BK7".into(),
        ior: [1.52; 3],
    });
    let mut model = built();
    model.objects[0].material.glass = glass.clone();
    assert_eq!(paths(&model), ["objects[0].shape"], "a glass plane");
    model.objects[0].shape = Shape::Sphere { radius: 0.1 };
    assert_eq!(paths(&model), Vec::<String>::new(), "a glass sphere");
    model.objects[0].scale = DVec3::new(1.0, 1.0, 0.5);
    assert_eq!(
        paths(&model),
        ["objects[0].scale"],
        "a squashed glass sphere"
    );
    model.objects[0].shape = Shape::Cylinder {
        radius: 0.1,
        height: 0.3,
    };
    assert_eq!(
        paths(&model),
        Vec::<String>::new(),
        "a glass cylinder, stretched"
    );
    model.objects[0].scale = DVec3::new(1.0, 0.5, 1.0);
    assert_eq!(
        paths(&model),
        ["objects[0].scale"],
        "an elliptic glass cylinder"
    );
}

#[test]
fn a_back_end_refuses_an_invalid_model_and_writes_nothing() {
    let mut model = built();
    model.cameras[0].cy = f64::INFINITY;
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("render");
    let err = Backend::Native
        .render(&model, &dir, &RenderOptions::default())
        .expect_err("an infinite cy must be refused");
    assert!(
        err.contains("the model is not valid") && err.contains("cameras[0].cy"),
        "{err}"
    );
    assert!(!dir.exists(), "nothing may be written");
    // The in-memory render (the Python module's `Scene.render`) checks it too.
    let err = poser::backend::native::render_one(&model, 0, 0, Some(1)).unwrap_err();
    assert!(err.contains("cameras[0].cy"), "{err}");
    for backend in [Backend::Mitsuba, Backend::Blender] {
        let err = backend.compile(&model, &dir).unwrap_err();
        assert!(err.contains("cameras[0].cy"), "{backend}: {err}");
        assert!(!dir.exists(), "{backend}: nothing may be written");
    }
}
