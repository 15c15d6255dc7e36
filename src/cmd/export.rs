//! `glint export SCENE -o DIR`: the prepared scene as Mitsuba 3 XML and PLY
//! meshes ([`glint::mitsuba`]).

use anyhow::Result;

use super::{check_params, load_scene};
use crate::cli::ExportArgs;

pub fn run(args: &ExportArgs) -> Result<()> {
    check_params(&args.scene)?;
    let (scene, opts) = load_scene(&args.scene)?;
    let out = glint::mitsuba::export(&scene, &opts, &args.dir)?;
    for w in &out.warnings {
        eprintln!("glint: warning: {}: {w}", args.scene.scene.display());
    }
    eprintln!(
        "glint: wrote {} ({} files) for Mitsuba 3",
        args.dir.join("scene.xml").display(),
        out.files.len()
    );
    Ok(())
}
