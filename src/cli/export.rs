//! `splitray export-scene`.

use std::path::PathBuf;

use clap::Args;
use splitray::scene::{validate, FilmSize, Location};

use super::paths::check_output;

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A built-in scene name (see `splitray scenes`), a scene .toml or an .obj mesh.
    scene: String,
    /// The JSON file to write (atomically).
    #[arg(short, long, value_name = "SCENE.json")]
    output: PathBuf,
    /// Film width in pixels (default: the scene's).
    #[arg(long)]
    width: Option<u32>,
    /// Film height in pixels (default: the scene's).
    #[arg(long)]
    height: Option<u32>,
}

pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    check_output(&args.output, &["json"], "a .json file")?;
    let scene = splitray::scene::load(&args.scene)?;
    let film = FilmSize {
        width: args.width.unwrap_or(scene.film.width),
        height: args.height.unwrap_or(scene.film.height),
    };
    validate::validate_film(&film, &Location::file("--width/--height"))?;
    let export = splitray::scene_export::export(&scene, film);
    let mut json = serde_json::to_vec_pretty(&export)?;
    json.push(b'\n');
    // The error names the file.
    splitray::film::atomic::write_bytes_atomically(&args.output, &json)?;
    splitray::outln!(
        "{}: {} triangles, {} materials, {} point lights, film {}x{} -> {}",
        export.name,
        export.triangles.len(),
        export.materials.len(),
        export.point_lights.len(),
        film.width,
        film.height,
        args.output.display()
    );
    Ok(())
}
