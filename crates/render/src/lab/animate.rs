//! `nlrt animate`: a scene's base mesh in motion ([`crate::scene::motion`]), frame by frame.
//!
//! Nonlinear tracing keeps the displacement in texture space, so per frame only the TLAS over
//! the prisms follows the new pose (refitted, or rebuilt by [`TlasUpdate`]); the min-max
//! pyramid or the shell object's BVH is never touched. Every other method is built afresh
//! on the posed mesh each frame: the pre-tessellated reference re-displaces and rebuilds its
//! microtriangles, Embree rebuilds its BVH over them (a refit would need the same
//! re-displacement first). Per frame and method: the update time, the TLAS's SAH cost
//! against a fresh build's, the render time, and (unless turned off) a check that every
//! primary hit equals that of a fresh build of the same frame.

use crate::lab::median;
use crate::scene::scenes::Scene;
use crate::trace::image::write_png;
use crate::trace::integrator::{self, Frame, RenderOptions};
use crate::trace::method::Method;
use crate::trace::methods::Nonlinear;
use crate::trace::objects::ObjectUnion;
use crate::trace::tracer::Tracer;
use nlrt_accel::TlasUpdate;
use nlrt_poly::Real;
use std::path::PathBuf;
use std::time::Instant;

/// Settings of `nlrt animate`.
#[derive(Clone, Debug)]
pub struct AnimateOptions {
    /// Frames (one cycle of a deformation).
    pub frames: usize,
    /// Image settings per frame.
    pub render: RenderOptions,
    /// Methods, each rendering every frame (nonlinear tracing) or the first
    /// [`AnimateOptions::rebuild_frames`] frames (methods rebuilt per frame).
    pub methods: Vec<Method>,
    /// How nonlinear tracing's TLAS follows each pose.
    pub update: TlasUpdate,
    /// Frames rendered by the methods that are rebuilt per frame (their rebuild does not
    /// depend on the pose, and at paper size costs seconds and gigabytes).
    pub rebuild_frames: usize,
    /// Also build nonlinear tracing afresh every frame, render with it and compare every
    /// primary hit with the updated surface's.
    pub verify: bool,
    /// Directory of the frames (`<scene>-<method>-<frame>.png`) and `animate.md`.
    pub out_dir: Option<PathBuf>,
}

impl Default for AnimateOptions {
    fn default() -> Self {
        Self {
            frames: 16,
            render: RenderOptions::default(),
            methods: vec![
                Method::NONLINEAR_F32,
                Method::NONLINEAR_F64,
                Method::TESSELLATED_F64,
            ],
            update: TlasUpdate::DEFAULT,
            rebuild_frames: 2,
            verify: true,
            out_dir: None,
        }
    }
}

/// A fresh build of the same frame, beside a pose update.
#[derive(Clone, Copy, Debug)]
pub struct FreshBuild {
    /// Seconds to build the surface from scratch on the posed mesh.
    pub build_seconds: f64,
    /// Seconds of the render with it.
    pub render_seconds: f64,
    /// The updated TLAS's SAH cost over the fresh one's.
    pub sah_ratio: f64,
    /// Pixels whose primary hit distance differs between the two (0 when the update is
    /// right).
    pub mismatches: usize,
}

/// One frame of one method.
#[derive(Clone, Debug)]
pub struct FrameRow {
    /// Frame number.
    pub frame: usize,
    /// Method.
    pub method: Method,
    /// What the update did: `refit`, `rebuild` (nonlinear tracing's TLAS), or `build` (the
    /// whole method built afresh).
    pub update: &'static str,
    /// Seconds of the update (pose update, or the whole build).
    pub update_seconds: f64,
    /// Seconds of the frame's render.
    pub render_seconds: f64,
    /// Rays cast by the render.
    pub rays: u64,
    /// The fresh build it was checked against (nonlinear tracing with verification).
    pub fresh: Option<FreshBuild>,
}

impl FrameRow {
    /// Millions of rays per second of the render.
    #[must_use]
    pub fn mrays(&self) -> f64 {
        self.rays as f64 / self.render_seconds / 1e6
    }
}

/// What `nlrt animate` measured.
#[derive(Clone, Debug)]
pub struct AnimateReport {
    /// Scene name.
    pub scene: String,
    /// The scene's motion, described.
    pub motion: String,
    /// Base triangles (prisms).
    pub prisms: usize,
    /// The settings.
    pub options: AnimateOptions,
    /// Every frame of every method, in the order rendered.
    pub rows: Vec<FrameRow>,
}

/// Pixels whose primary hit distance differs (bit for bit; NaN is no hit).
fn depth_mismatches(a: &Frame, b: &Frame) -> usize {
    a.depth
        .iter()
        .zip(&b.depth)
        .filter(|(x, y)| x.to_bits() != y.to_bits())
        .count()
}

/// Renders the scene's motion over the frames with every method.
///
/// # Errors
/// A static scene, no frames, a method that cannot render the scene, a pose that is not
/// finite in a method's precision, or a frame that cannot be written.
pub fn run(scene: &Scene, opts: &AnimateOptions) -> Result<AnimateReport, String> {
    if opts.frames == 0 {
        return Err("at least one frame is needed".into());
    }
    if scene.pose(0, opts.frames).is_none() {
        return Err(format!(
            "scene '{}' has no motion: give its file an [animation] section (frames or a deformation) or pass --deformation",
            scene.name
        ));
    }
    for &m in &opts.methods {
        if let Some(why) = m.unsupported_reason(scene) {
            return Err(format!("{m} cannot render {}: {why}", scene.name));
        }
    }
    if let Some(dir) = &opts.out_dir {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let mut rows = Vec::new();
    for &method in &opts.methods {
        match method {
            Method::NONLINEAR_F32 => animate_nonlinear::<f32>(scene, method, opts, &mut rows)?,
            Method::NONLINEAR_F64 => animate_nonlinear::<f64>(scene, method, opts, &mut rows)?,
            _ => animate_rebuilt(scene, method, opts, &mut rows)?,
        }
    }
    Ok(AnimateReport {
        scene: scene.name.to_string(),
        motion: scene.motion.describe(),
        prisms: scene.triangle_count(),
        options: opts.clone(),
        rows,
    })
}

fn write_frame(
    opts: &AnimateOptions,
    scene: &Scene,
    method: Method,
    k: usize,
    frame: &Frame,
) -> Result<(), String> {
    let Some(dir) = &opts.out_dir else {
        return Ok(());
    };
    let path = dir.join(format!("{}-{}-{k:04}.png", scene.name, method.slug()));
    write_png(&path, frame.width, frame.height, &frame.rgb8())
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn progress(row: &FrameRow, frames: usize) {
    let fresh = row.fresh.map_or(String::new(), |f| {
        format!(
            ", fresh build {:.2} ms, SAH x{:.3}, {} pixels differ",
            f.build_seconds * 1e3,
            f.sah_ratio,
            f.mismatches
        )
    });
    eprintln!(
        "frame {}/{frames} {}: {} {:.3} ms, render {:.3} s ({:.2} Mrays/s){fresh}",
        row.frame + 1,
        row.method,
        row.update,
        row.update_seconds * 1e3,
        row.render_seconds,
        row.mrays()
    );
}

/// An object's pose in `T`: positions and normals.
type PoseIn<T> = (Vec<<T as Real>::Vec3>, Vec<<T as Real>::Vec3>);

/// Nonlinear tracing of every object in `T`, traced as one.
fn nonlinear_objects<T: Real>(scene: &Scene) -> ObjectUnion<Nonlinear<T>> {
    ObjectUnion::new(
        scene
            .objects()
            .map(|object| (Nonlinear::<T>::new(object), object.triangles.len())),
    )
}

/// The sum of the objects' TLAS SAH costs.
fn sah_cost<T: Real>(objects: &ObjectUnion<Nonlinear<T>>) -> f64 {
    objects.tracers().map(Nonlinear::tlas_sah_cost).sum()
}

/// Nonlinear tracing in `T`: built once on the rest pose, then one pose update per frame
/// (of every object's TLAS, for a scene of several objects).
fn animate_nonlinear<T: Real>(
    scene: &Scene,
    method: Method,
    opts: &AnimateOptions,
    rows: &mut Vec<FrameRow>,
) -> Result<(), String> {
    use nlrt_poly::Vector3;
    scene.check_precision::<T>()?;
    let mut tracer = nonlinear_objects::<T>(scene);
    let v = |p: &nlrt_poly::glam::DVec3| {
        T::Vec3::new(T::from_f64(p.x), T::from_f64(p.y), T::from_f64(p.z))
    };
    for k in 0..opts.frames {
        let posed_scene = scene.posed_at(k, opts.frames)?;
        // The conversion to `T` is the caller's (an animation system hands over its own
        // arrays); the update timed is the surface's.
        let poses: Vec<PoseIn<T>> = posed_scene
            .objects()
            .map(|o| {
                (
                    o.positions.iter().map(v).collect(),
                    o.normals.iter().map(v).collect(),
                )
            })
            .collect();
        let start = Instant::now();
        let mut rebuilt = false;
        let mut updated_cost = 0.0;
        for (object, (positions, normals)) in tracer.tracers_mut().zip(&poses) {
            let done = object.set_pose_in_precision(positions, normals, opts.update)?;
            rebuilt |= done.rebuilt;
            updated_cost += done.sah_cost;
        }
        let update_seconds = start.elapsed().as_secs_f64();
        let render = |t: &dyn Tracer| integrator::render(&posed_scene, t, &opts.render, &|_| {});
        let fresh_build = || -> Result<(ObjectUnion<Nonlinear<T>>, f64), String> {
            posed_scene.check_precision::<T>()?;
            let start = Instant::now();
            let fresh = nonlinear_objects::<T>(&posed_scene);
            Ok((fresh, start.elapsed().as_secs_f64()))
        };
        // Interleaved: the frame's two renders alternate which goes first, so neither
        // always finds the caches warm.
        let (frame, fresh) = if opts.verify {
            let (fresh, build_seconds) = fresh_build()?;
            let (frame, fresh_frame) = if k % 2 == 0 {
                let f = render(&tracer);
                (f, render(&fresh))
            } else {
                let g = render(&fresh);
                (render(&tracer), g)
            };
            let check = FreshBuild {
                build_seconds,
                render_seconds: fresh_frame.seconds,
                sah_ratio: updated_cost / sah_cost(&fresh),
                mismatches: depth_mismatches(&frame, &fresh_frame),
            };
            (frame, Some(check))
        } else {
            (render(&tracer), None)
        };
        write_frame(opts, scene, method, k, &frame)?;
        let row = FrameRow {
            frame: k,
            method,
            update: if rebuilt { "rebuild" } else { "refit" },
            update_seconds,
            render_seconds: frame.seconds,
            rays: frame.all_rays,
            fresh,
        };
        progress(&row, opts.frames);
        rows.push(row);
    }
    Ok(())
}

/// A method without pose updates: built afresh on each posed mesh.
fn animate_rebuilt(
    scene: &Scene,
    method: Method,
    opts: &AnimateOptions,
    rows: &mut Vec<FrameRow>,
) -> Result<(), String> {
    if method.precision() == crate::trace::method::Precision::F32 {
        scene.check_precision::<f32>()?;
    }
    for k in 0..opts.frames.min(opts.rebuild_frames) {
        let posed_scene = scene.posed_at(k, opts.frames)?;
        let start = Instant::now();
        let tracer = method
            .build(&posed_scene)
            .ok_or_else(|| format!("{method} cannot render {}", scene.name))?;
        let update_seconds = start.elapsed().as_secs_f64();
        let frame = integrator::render(&posed_scene, tracer.as_ref(), &opts.render, &|_| {});
        drop(tracer);
        write_frame(opts, scene, method, k, &frame)?;
        let row = FrameRow {
            frame: k,
            method,
            update: "build",
            update_seconds,
            render_seconds: frame.seconds,
            rays: frame.all_rays,
            fresh: None,
        };
        progress(&row, opts.frames);
        rows.push(row);
    }
    Ok(())
}

/// Per method over its frames: median and largest update, rebuilds, median render, and the
/// checks against fresh builds.
#[derive(Clone, Debug)]
pub struct MethodSummary {
    /// Method.
    pub method: Method,
    /// Frames rendered.
    pub frames: usize,
    /// Median seconds of an update.
    pub update_median: f64,
    /// Largest seconds of an update.
    pub update_max: f64,
    /// Frames whose TLAS (or whole method) was built afresh.
    pub builds: usize,
    /// Median render seconds.
    pub render_median: f64,
    /// Sum of render seconds over the sum of the fresh builds' render seconds (verified
    /// nonlinear tracing only).
    pub render_ratio: Option<f64>,
    /// Median and largest SAH cost ratio against fresh builds.
    pub sah_ratio: Option<(f64, f64)>,
    /// Pixels whose hit differs from a fresh build's, over every frame.
    pub mismatches: Option<usize>,
    /// Median seconds of a fresh build (verified nonlinear tracing only).
    pub fresh_build_median: Option<f64>,
}

/// The summary per method, in the order of the options.
#[must_use]
pub fn summarise(report: &AnimateReport) -> Vec<MethodSummary> {
    let mut out = Vec::new();
    for &method in &report.options.methods {
        let rows: Vec<&FrameRow> = report.rows.iter().filter(|r| r.method == method).collect();
        if rows.is_empty() {
            continue;
        }
        let fresh: Vec<FreshBuild> = rows.iter().filter_map(|r| r.fresh).collect();
        let verified = !fresh.is_empty();
        let sum = |f: &dyn Fn(&FrameRow) -> f64| rows.iter().map(|r| f(r)).sum::<f64>();
        out.push(MethodSummary {
            method,
            frames: rows.len(),
            update_median: median(rows.iter().map(|r| r.update_seconds).collect()).unwrap_or(0.0),
            update_max: rows.iter().map(|r| r.update_seconds).fold(0.0, f64::max),
            builds: rows.iter().filter(|r| r.update != "refit").count(),
            render_median: median(rows.iter().map(|r| r.render_seconds).collect()).unwrap_or(0.0),
            render_ratio: verified.then(|| {
                sum(&|r| r.render_seconds) / fresh.iter().map(|f| f.render_seconds).sum::<f64>()
            }),
            sah_ratio: verified.then(|| {
                (
                    median(fresh.iter().map(|f| f.sah_ratio).collect()).unwrap_or(1.0),
                    fresh.iter().map(|f| f.sah_ratio).fold(0.0, f64::max),
                )
            }),
            mismatches: verified.then(|| fresh.iter().map(|f| f.mismatches).sum()),
            fresh_build_median: median(fresh.iter().map(|f| f.build_seconds).collect()),
        });
    }
    out
}

/// The report as Markdown: the summary per method, then every frame.
#[must_use]
pub fn markdown(report: &AnimateReport) -> String {
    let o = &report.options;
    let ms = |s: f64| format!("{:.3} ms", s * 1e3);
    let update_rule = match o.update {
        TlasUpdate::Refit => "refit every frame".to_string(),
        TlasUpdate::Rebuild => "rebuilt every frame".to_string(),
        TlasUpdate::Auto { max_cost_growth } => {
            format!("refit, rebuilt when its SAH cost grows past {max_cost_growth}x")
        }
    };
    let mut md = format!(
        "Scene `{}` ({} base triangles), motion {}, {} frames at {}x{}, {} spp, {} bounces; \
         nonlinear tracing's TLAS {update_rule}; other methods built afresh per frame (first {} \
         frames).\n\n",
        report.scene,
        report.prisms,
        report.motion,
        o.frames,
        o.render.width,
        o.render.height,
        o.render.spp,
        o.render.bounces,
        o.rebuild_frames.min(o.frames),
    );
    md.push_str(
        "| method | frames | update per frame: median (max) | TLAS rebuilds / builds | render median | render / fresh build's | SAH cost / fresh build's: median (max) | pixels differing from a fresh build |\n|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let summaries = summarise(report);
    for s in &summaries {
        let opt = |v: Option<String>| v.unwrap_or_else(|| "-".into());
        md.push_str(&format!(
            "| {} | {} | {} ({}) | {} | {:.3} s | {} | {} | {} |\n",
            s.method,
            s.frames,
            ms(s.update_median),
            ms(s.update_max),
            s.builds,
            s.render_median,
            opt(s.render_ratio.map(|r| format!("{r:.3}"))),
            opt(s.sah_ratio.map(|(m, x)| format!("{m:.3} ({x:.3})"))),
            opt(s.mismatches.map(|m| m.to_string())),
        ));
    }
    // Against each rebuilt method: how many times faster nonlinear tracing's update is.
    let rebuilt: Vec<&MethodSummary> = summaries
        .iter()
        .filter(|s| !matches!(s.method, Method::NONLINEAR_F32 | Method::NONLINEAR_F64))
        .collect();
    for n in summaries
        .iter()
        .filter(|s| matches!(s.method, Method::NONLINEAR_F32 | Method::NONLINEAR_F64))
    {
        for r in &rebuilt {
            md.push_str(&format!(
                "\n{}'s update per frame is {:.0}x faster than {}'s rebuild.",
                n.method,
                r.update_median / n.update_median.max(1e-9),
                r.method
            ));
        }
    }
    md.push_str(
        "\n\n| frame | method | update | time | render | Mrays/s | fresh build | SAH / fresh | pixels differing |\n|---:|---|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in &report.rows {
        let (build, sah, diff) = r.fresh.map_or(("-".into(), "-".into(), "-".into()), |f| {
            (
                ms(f.build_seconds),
                format!("{:.3}", f.sah_ratio),
                f.mismatches.to_string(),
            )
        });
        md.push_str(&format!(
            "| {} | {} | {} | {} | {:.3} s | {:.2} | {build} | {sah} | {diff} |\n",
            r.frame,
            r.method,
            r.update,
            ms(r.update_seconds),
            r.render_seconds,
            r.mrays()
        ));
    }
    md
}
