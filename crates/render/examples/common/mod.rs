//! Command-line helpers shared by the traversal examples (`traversal_counts`,
//! `stream_counts`, `leaving_counts`): a built-in scene by name and map size, a width, the
//! exit-2 message, and the median of timed rounds.

use nlrt_render::scene::scenes::{Scene, Size, builtin};

/// Prints `program: message` and exits with code 2.
pub fn fail(program: &str, message: &str) -> ! {
    eprintln!("{program}: {message}");
    std::process::exit(2);
}

/// The built-in scene named by `args[1]` (default `mountain`) at the map size of `args[2]`
/// (`small`, the default, or `paper`), with its name.
pub fn scene_from_args<'a>(args: &'a [String], program: &str) -> (&'a str, Scene) {
    let name = args.get(1).map_or("mountain", String::as_str);
    let size = match args.get(2).map(String::as_str) {
        None | Some("small") => Size::Small,
        Some("paper") => Size::Paper,
        Some(other) => fail(program, &format!("unknown size {other} (small or paper)")),
    };
    let Some(scene) = builtin(name, size) else {
        fail(program, &format!("unknown scene {name}"));
    };
    (name, scene)
}

/// A width in pixels from `args[index]` (`default` when absent), from 4 to 4096.
pub fn width_from_args(args: &[String], index: usize, default: usize, program: &str) -> usize {
    match args.get(index).map(|s| s.parse::<usize>()) {
        None => default,
        Some(Ok(w)) if (4..=4096).contains(&w) => w,
        Some(_) => fail(program, "pixels per row: a number from 4 to 4096"),
    }
}

/// Median of `xs` ([`nlrt_render::lab::median`]; NaN when empty: a variant left out).
// `traversal_counts` times no rounds.
#[allow(dead_code)]
#[must_use]
pub fn median(xs: Vec<f64>) -> f64 {
    nlrt_render::lab::median(xs).unwrap_or(f64::NAN)
}
