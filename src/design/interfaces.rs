//! The interfaces a design chooses among, as a designer names them: `[[interface]]` tables in
//! a device file's `[interface]` form (`endstop design --interfaces FILE`, and dicts in
//! Python), or a name, `resistive` or the key of the device's own interface.
//!
//! Each table is put in place of the device's `[interface]` (the transducer's own load
//! removed behind a circuit) and the device is checked with it, so that an error names the
//! source, the table and the field as a device file's would.

use crate::device::{Device, Interface, ParamError};

use super::DesignError;

/// The interfaces of `[[interface]]` tables (each as a device file's `[interface]`;
/// `kind = "resistive"` for the transducer's own load) for `device`; `source` names them in
/// errors (a file, say).
pub fn from_tables(
    device: &Device,
    tables: &[toml::Table],
    source: &str,
) -> Result<Vec<Interface>, DesignError> {
    let base: toml::Table = toml::from_str(&device.to_toml_string())
        .map_err(|e| DesignError::Invalid(format!("{source}: the device as TOML: {e}")))?;
    tables
        .iter()
        .enumerate()
        .map(|(i, table)| {
            if table.get("kind").and_then(|k| k.as_str()) == Some("resistive") {
                return Ok(Interface::Resistive);
            }
            let mut t = base.clone();
            t.insert("interface".into(), toml::Value::Table(table.clone()));
            if let Some(tr) = t.get_mut("transducer").and_then(|v| v.as_table_mut()) {
                tr.remove("load_resistance_ohm");
            }
            let text = toml::to_string(&t)
                .map_err(|e| DesignError::Invalid(format!("{source}, interface {}: {e}", i + 1)))?;
            Device::from_toml_str(&text, &format!("{source}, interface {}", i + 1))
                .map(|d| d.interface)
                .map_err(DesignError::Interface)
        })
        .collect()
}

/// The interfaces of a TOML text of `[[interface]]` tables only (the file of
/// `endstop design --interfaces`); `source` names it in errors.
pub fn from_toml_str(
    device: &Device,
    text: &str,
    source: &str,
) -> Result<Vec<Interface>, DesignError> {
    let bad = |m: String| DesignError::Invalid(format!("{source}: {m}"));
    let doc: toml::Table = toml::from_str(text).map_err(|e| bad(format!("not TOML: {e}")))?;
    let Some(list) = doc.get("interface").and_then(|v| v.as_array()) else {
        return Err(bad("has no [[interface]] tables".into()));
    };
    if doc.len() != 1 {
        return Err(bad("may hold [[interface]] tables only".into()));
    }
    let tables = list
        .iter()
        .enumerate()
        .map(|(i, v)| {
            v.as_table()
                .cloned()
                .ok_or_else(|| bad(format!("interface {} is not a table", i + 1)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    from_tables(device, &tables, source)
}

/// The interface a name stands for on `device`: `resistive` (the transducer's own load), or
/// the key of the device's own interface (that circuit, with its file's values). Any other
/// name is refused, naming the two a name can be: another circuit needs its values, as a
/// table ([`from_tables`]).
pub fn by_name(device: &Device, name: &str) -> Result<Interface, DesignError> {
    if name == Interface::Resistive.key() {
        return Ok(Interface::Resistive);
    }
    if name == device.interface.key() {
        return Ok(device.interface.clone());
    }
    Err(DesignError::Interface(ParamError::Invalid {
        source_name: "interfaces".into(),
        field: name.to_string(),
        message: format!(
            "a name is `resistive` or the device's own interface `{}`; give another circuit \
             as a table of its values (a device file's [interface])",
            device.interface.key()
        ),
    }))
}
