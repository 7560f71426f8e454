//! Units and axis labels of a model's signals, for text and plots.

use leeway_structure::ir::Ir;

/// The declared units, one line each: `delta: column rudder_deg in deg, converted to rad`.
pub fn unit_lines(ir: &Ir) -> Vec<String> {
    ir.data_units
        .iter()
        .map(|(signal, unit)| {
            let column = leeway_model::experiment::column_name(ir, signal);
            let base = leeway_structure::units::unit(unit).map_or("?", |(k, _)| k.base());
            if base == unit {
                format!("{signal}: column {column} in {unit}, read as is")
            } else {
                format!("{signal}: column {column} in {unit}, converted to {base}")
            }
        })
        .collect()
}

/// The unit an axis shows for a signal: the base unit its declared unit
/// converts to, or none (then the axis names the signal only: leeway does
/// not assume what an undeclared column measures).
pub fn axis_label(ir: &Ir, signal: &str) -> String {
    match ir
        .data_units
        .get(signal)
        .and_then(|u| leeway_structure::units::unit(u))
    {
        Some((kind, _)) => format!("{signal} ({})", kind.base()),
        None => signal.to_string(),
    }
}
