//! The subcommands of the `ridgeline` binary: `fly` (the main job) flies a
//! camera path over a terrain, `accuracy` measures the error it draws against
//! full resolution, `import` builds a node pyramid cache, `info` describes
//! one. Helpers shared by the subcommands live here.

use std::path::Path;

use anyhow::Result;
use glam::UVec2;
use ridgeline::flight::{builtin_approach, FlightPath};
use ridgeline::node::NodeSource as _;
use ridgeline::pyramid::Pyramid;

pub mod accuracy;
pub mod fly;
pub mod import;
pub mod info;
mod progress;

/// Writes `text` to standard output. A reader that has gone away (a closed
/// pipe, as in `ridgeline info ... | head`) is not an error.
pub fn print(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(error) if error.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => Ok(other?),
    }
}

/// Parses `--size WIDTHxHEIGHT`.
fn parse_size(text: &str) -> Result<UVec2, String> {
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| format!("size `{text}` is not WIDTHxHEIGHT"))?;
    let parse = |s: &str| s.trim().parse::<u32>().map_err(|_| format!("size `{text}`: `{s}` is not a whole number"));
    let size = UVec2::new(parse(w)?, parse(h)?);
    if size.x == 0 || size.y == 0 || size.x > 16384 || size.y > 16384 {
        return Err(format!("size `{text}` must be between 1x1 and 16384x16384"));
    }
    Ok(size)
}

/// The camera path of a run: the CSV at `path`, else the built-in approach
/// over `pyramid`.
fn flight_path(path: Option<&Path>, pyramid: &Pyramid) -> Result<FlightPath> {
    let layout = *pyramid.layout();
    match path {
        Some(file) => Ok(FlightPath::read(file, &pyramid.info().georef, layout.samples)?),
        None => {
            let height = |x: f64, y: f64| pyramid.exact_height(x, y).unwrap_or(0.0);
            Ok(builtin_approach(layout.extent_m(), &height))
        }
    }
}
