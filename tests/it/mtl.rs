//! How MTL materials map onto ours: glass, mirrors and emission as before,
//! and the glossy keys (`illum 2` with `Ks` and `Ns`; the PBR extension's
//! `Pr` and `Pm`) onto plastic and conductors, as docs/scene-format.md says.

use crate::common::write;
use tracer::color::Rgb;
use tracer::material::{Albedo, Material};

fn load(mtl: &str) -> tracer::scene::Scene {
    let dir = tempfile::tempdir().unwrap();
    let names = ["plain", "phong", "phong-off", "metal", "pbr", "pbr-glass"];
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for n in names {
        obj += &format!("usemtl {n}\nf 1 2 3\n");
    }
    write(&dir.path().join("m.obj"), obj);
    write(&dir.path().join("m.mtl"), mtl);
    let scene = write(
        &dir.path().join("s.json"),
        r#"{"camera": {"position": [0, 0, -3], "look_at": [0, 0, 0]},
            "objects": [{"type": "mesh", "file": "m.obj"}],
            "lights": [{"type": "point", "position": [0, 0, -1], "intensity": [1, 1, 1]}]}"#,
    );
    tracer::scene::load(&scene).unwrap().0
}

fn material<'a>(scene: &'a tracer::scene::Scene, name: &str) -> &'a Material {
    let i = scene
        .material_names
        .iter()
        .position(|n| n == &format!("m.obj:{name}"))
        .unwrap_or_else(|| panic!("no material {name} in {:?}", scene.material_names));
    &scene.materials[i]
}

#[test]
fn glossy_mtl_keys_make_plastics_and_metals() {
    let scene = load(
        "newmtl plain\nKd 0.5 0.4 0.3\nKs 0 0 0\nNs 50\nillum 2\n\
         newmtl phong\nKd 0.2 0.3 0.4\nKs 0.5 0.5 0.5\nNs 98\nNi 1.45\nillum 2\n\
         newmtl phong-off\nKd 0.2 0.3 0.4\nKs 0.5 0.5 0.5\nNs 98\nillum 1\n\
         newmtl metal\nKd 0.9 0.6 0.2\nPm 1\nPr 0.4\n\
         newmtl pbr\nKd 0.1 0.5 0.1\nPm 0\nPr 0.3\n\
         newmtl pbr-glass\nKd 1 1 1\nPr 0.3\nillum 7\nNi 1.5\n",
    );
    assert!(matches!(
        material(&scene, "plain"),
        Material::Diffuse { .. }
    ));
    assert!(matches!(
        material(&scene, "phong-off"),
        Material::Diffuse { .. }
    ));
    match material(&scene, "phong") {
        Material::Plastic {
            albedo: Albedo::Constant(c),
            ior,
            alpha,
            ..
        } => {
            assert_eq!(*c, Rgb::new(0.2, 0.3, 0.4));
            assert_eq!(*ior, 1.45);
            assert!((alpha - (2.0f32 / 100.0).sqrt()).abs() < 1e-6, "{alpha}");
        }
        m => panic!("phong: {m:?}"),
    }
    match material(&scene, "metal") {
        Material::Conductor {
            alpha,
            eta,
            k,
            reflectance,
        } => {
            assert!((alpha - 0.16).abs() < 1e-6);
            assert_eq!((*eta, *k), (Rgb::ZERO, Rgb::ONE), "Fresnel 1");
            assert_eq!(*reflectance, Rgb::new(0.9, 0.6, 0.2));
        }
        m => panic!("metal: {m:?}"),
    }
    match material(&scene, "pbr") {
        Material::Plastic { ior, alpha, .. } => {
            assert_eq!(*ior, 1.5);
            assert!((alpha - 0.09).abs() < 1e-6);
        }
        m => panic!("pbr: {m:?}"),
    }
    // Glass stays glass.
    assert!(matches!(
        material(&scene, "pbr-glass"),
        Material::Dielectric { .. }
    ));
}
