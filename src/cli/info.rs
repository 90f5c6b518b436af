//! `tracer info`: what a scene holds (triangles, lights, materials,
//! bounds, BVH) and what a render of it would do.

use super::cache::CacheArgs;
use tracer::format::read_scene;
use tracer::light::Light;
use tracer::scene::build;
use tracer::scene::cache::CacheUse;
use tracer::Result;

/// Prints what the scene holds and what a render of it would do.
pub fn run_info(path: &std::path::Path, cache: &CacheArgs) -> Result<()> {
    let desc = read_scene(path)?;
    let scene = build(&desc, cache.cache().as_ref())?;
    let count = |f: fn(&Light) -> bool| scene.lights.iter().filter(|l| f(l)).count();
    outln!("scene:      {} ({})", scene.name, path.display());
    outln!("triangles:  {}", scene.triangles.len());
    if scene.report.degenerate_triangles_dropped > 0 {
        outln!(
            "dropped:    {} degenerate triangles",
            scene.report.degenerate_triangles_dropped
        );
    }
    outln!(
        "lights:     {} (area triangles {}, point {}, spot {}, directional {}, environment {})",
        scene.lights.len(),
        count(|l| matches!(l, Light::Area(_))),
        count(|l| matches!(l, Light::Point(_))),
        count(|l| matches!(l, Light::Spot(_))),
        count(|l| matches!(l, Light::Directional(_))),
        count(|l| matches!(l, Light::Environment(_))),
    );
    outln!(
        "materials:  {} ({})",
        scene.materials.len(),
        scene.material_names.join(", ")
    );
    let b = scene.bounds;
    if b.is_empty() {
        outln!("bounds:     empty");
    } else {
        outln!(
            "bounds:     ({:.4}, {:.4}, {:.4}) .. ({:.4}, {:.4}, {:.4})",
            b.min.x,
            b.min.y,
            b.min.z,
            b.max.x,
            b.max.y,
            b.max.z
        );
    }
    let r = scene.bvh.report();
    outln!(
        "bvh:        {}-wide, {} nodes, {} leaves, SAH cost {:.2} (binary {:.2}), {} bytes, {}",
        tracer::bvh::wide::WIDTH,
        r.nodes,
        r.leaves,
        r.sah_cost,
        r.binary_sah_cost,
        scene.bvh.memory_bytes(),
        match scene.report.cache {
            CacheUse::Hit => "from the scene cache".to_string(),
            _ => format!("built in {:.3} s", scene.report.bvh_build_seconds),
        }
    );
    if scene.bvh.is_flat() {
        outln!(
            "            traced flat: at most {} triangles, each ray tests them all",
            tracer::bvh::wide::FLAT_MAX_TRIANGLES
        );
    }
    let s = &desc.settings;
    outln!(
        "render:     {}x{}, {} spp, {}, max depth {}, seed {} -> {}",
        s.film.width,
        s.film.height,
        s.stop.spp,
        s.integrator.name(),
        s.max_depth,
        s.seed,
        s.film.output.display()
    );
    for w in &scene.report.warnings {
        outln!("warning:    {w}");
    }
    Ok(())
}
