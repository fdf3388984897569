//! `antenna optimize --scene-out FILE.toml`: the first scene with the stiffnesses found, as
//! a scene file `antenna sweep` reads (its comments and layout kept; the stiffness given as
//! `values_n_m_per_rad`; the optimization's `duration_s`; a `points_file` made absolute, so
//! the file can live anywhere).

use std::path::Path;

use toml_edit::{Array, DocumentMut, Item, Table, value};

use super::{OptimizeReport, OptimizeSpec};

/// The first scene's text with `report`'s stiffnesses.
///
/// # Errors
/// A sentence when the scene file cannot be read again or is no longer TOML.
pub fn best_scene_text(spec: &OptimizeSpec, report: &OptimizeReport) -> Result<String, String> {
    let (path, scene) = &spec.scenes[0];
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read the scene again: {e}", path.display()))?;
    let mut doc: DocumentMut = text
        .parse()
        .map_err(|e| format!("{}: no longer TOML: {e}", path.display()))?;
    let antenna = doc
        .entry("antenna")
        .or_insert_with(|| Item::Table(Table::new()));
    let Some(antenna) = antenna.as_table_like_mut() else {
        return Err(format!("{}: [antenna] is not a table", path.display()));
    };
    let mut stiffness = Table::new();
    let values: Array = report.values_n_m_per_rad.iter().copied().collect();
    stiffness.insert("values_n_m_per_rad", value(values));
    stiffness.decor_mut().set_prefix(format!(
        "\n# found by `antenna optimize {}`: {} = {} {} ({})\n",
        spec.path.display(),
        report.objective,
        report
            .objective_value
            .map_or("infeasible".to_string(), |v| format!("{v}")),
        spec.objective.si_unit(),
        report.found_by
    ));
    antenna.insert("stiffness", Item::Table(stiffness));
    if let Some(sweep) = doc.get_mut("sweep").and_then(Item::as_table_like_mut) {
        sweep.insert("duration_s", value(scene.motion.duration_s));
    }
    if let Some(follow) = &scene.follow
        && let Some(table) = doc.get_mut("follow").and_then(Item::as_table_like_mut)
    {
        table.insert("duration_s", value(follow.config.settings.duration_s));
    }
    let folder = path.parent().unwrap_or_else(|| Path::new(""));
    if let Some(walls) = doc.get_mut("walls").and_then(Item::as_array_of_tables_mut) {
        for wall in walls.iter_mut() {
            if let Some(file) = wall.get("points_file").and_then(Item::as_str) {
                let absolute = std::path::absolute(folder.join(file))
                    .map_err(|e| format!("{}: {file}: {e}", path.display()))?;
                wall.insert("points_file", value(absolute.display().to_string()));
            }
        }
    }
    Ok(doc.to_string())
}
