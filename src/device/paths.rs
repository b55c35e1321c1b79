//! Device parameters named by their dotted path in the file form, so that a study (a
//! sensitivity analysis, a fit) can vary any of them: `mechanics.mass_kg`,
//! `transducer.bias_v`, `stops.upper.gap_m`, or `stops.both.gap_m` for both sides at once.
//!
//! The earlier format's names are accepted as aliases where they have one meaning in the
//! general description (`geometry.endstop_gap_m` is `stops.both.gap_m`, `electrical.bias_v`
//! is `transducer.bias_v`, ...).

use super::{Device, ParamError, RawDevice};

/// The earlier format's parameter names and their paths in the general description.
const ALIASES: [(&str, &str); 12] = [
    ("geometry.endstop_gap_m", "stops.both.gap_m"),
    ("geometry.bump_radius_m", "stops.both.bump_radius_m"),
    ("geometry.finger_overlap_m", "transducer.finger_overlap_m"),
    ("endstop.damping_n_s_per_m", "stops.both.damping_n_s_per_m"),
    (
        "endstop.linear_coefficient",
        "stops.both.linear_coefficient",
    ),
    ("material.youngs_modulus_pa", "stops.both.youngs_modulus_pa"),
    ("material.poisson_ratio", "stops.both.poisson_ratio"),
    ("electrical.c0_f", "transducer.c0_f"),
    ("electrical.cp_f", "transducer.cp_f"),
    (
        "electrical.load_resistance_ohm",
        "transducer.load_resistance_ohm",
    ),
    (
        "electrical.load_capacitance_f",
        "transducer.load_capacitance_f",
    ),
    ("electrical.bias_v", "transducer.bias_v"),
];

/// The path a name stands for (an alias resolved).
fn canonical(path: &str) -> &str {
    ALIASES
        .iter()
        .find(|(alias, _)| *alias == path)
        .map_or(path, |(_, p)| p)
}

fn unknown(path: &str, known: &[String]) -> ParamError {
    ParamError::Invalid {
        source_name: "parameter".into(),
        field: path.to_string(),
        message: format!(
            "no such numeric parameter in this device; its parameters are: {}",
            known.join(", ")
        ),
    }
}

impl Device {
    /// The file form with the stops always written per side (`stops.upper`, `stops.lower`).
    fn expanded_value(&self) -> toml::Table {
        if self.masses.is_some() {
            // Several masses: the file form, whose arrays (`masses.1.mass_kg`) index by number.
            return toml::from_str(&self.to_toml_string()).expect("a device's TOML reads back");
        }
        let mut raw = self.raw();
        raw.stops = super::stops::RawStops::expanded(&self.stops);
        toml::Table::try_from(&raw).expect("a device serialises to a TOML table")
    }

    /// The dotted paths of every numeric parameter of this device (stops per side, and
    /// `stops.both.*` where both sides have the key).
    pub fn param_paths(&self) -> Vec<String> {
        fn walk(prefix: &str, t: &toml::Table, out: &mut Vec<String>) {
            for (k, v) in t {
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                match v {
                    toml::Value::Table(inner) => walk(&p, inner, out),
                    toml::Value::Array(items) => {
                        for (i, item) in items.iter().enumerate() {
                            if let toml::Value::Table(inner) = item {
                                walk(&format!("{p}.{i}"), inner, out);
                            }
                        }
                    }
                    toml::Value::Float(_) | toml::Value::Integer(_) => out.push(p),
                    _ => {}
                }
            }
        }
        let mut out = Vec::new();
        walk("", &self.expanded_value(), &mut out);
        let both: Vec<String> = out
            .iter()
            .filter_map(|p| p.strip_prefix("stops.upper."))
            .filter(|k| out.contains(&format!("stops.lower.{k}")))
            .map(|k| format!("stops.both.{k}"))
            .collect();
        out.extend(both);
        out
    }

    /// The value of a numeric parameter by its dotted path (see the module docs); a
    /// `stops.both.*` path needs both sides to have the same value.
    pub fn param(&self, path: &str) -> Result<f64, ParamError> {
        let table = self.expanded_value();
        let path_c = canonical(path);
        let values: Vec<f64> = targets(path_c)
            .iter()
            .map(|p| lookup(&table, p))
            .collect::<Option<_>>()
            .ok_or_else(|| unknown(path, &self.param_paths()))?;
        if values.windows(2).any(|w| w[0] != w[1]) {
            return Err(ParamError::Invalid {
                source_name: "parameter".into(),
                field: path.to_string(),
                message: format!(
                    "the two stops differ ({:e} and {:e}): name `stops.upper.*` or `stops.lower.*`",
                    values[0], values[1]
                ),
            });
        }
        Ok(values[0])
    }

    /// A copy with a numeric parameter set by its dotted path, validated like a file. A yes/no
    /// switch (`stops.both.tension_free`) is set by 0 (no) or 1 (yes).
    ///
    /// ```
    /// # let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype2.toml")).unwrap();
    /// use endstop::device::Device;
    /// let dev = Device::from_toml_str(&text, "prototype2.toml").unwrap();
    /// let wider = dev.with_param("stops.both.gap_m", 9e-6).unwrap();
    /// assert_eq!(wider.param("stops.upper.gap_m").unwrap(), 9e-6);
    /// assert!(dev.with_param("stops.both.gap_m", -1.0).is_err());
    /// assert!(dev.with_param("mechanics.no_such_key", 1.0).is_err());
    /// ```
    pub fn with_param(&self, path: &str, value: f64) -> Result<Device, ParamError> {
        self.with_params(&[(path, value)])
    }

    /// A copy with several parameters set by their dotted paths (as [`Device::with_param`]),
    /// validated once, after all are set.
    pub fn with_params(&self, values: &[(&str, f64)]) -> Result<Device, ParamError> {
        let mut table = self.expanded_value();
        for &(path, value) in values {
            for p in targets(canonical(path)) {
                let slot =
                    lookup_mut(&mut table, &p).ok_or_else(|| unknown(path, &self.param_paths()))?;
                *slot = set(slot, path, value)?;
            }
        }
        let path = values
            .iter()
            .map(|(p, _)| *p)
            .collect::<Vec<_>>()
            .join("`, `");
        let text = toml::to_string(&table).expect("a TOML table serialises");
        if self.masses.is_some() {
            return Device::from_toml_str(&text, &format!("parameter `{path}`"));
        }
        let raw: RawDevice = toml::from_str(&text).map_err(|e| ParamError::Parse {
            source_name: format!("parameter `{path}`"),
            message: e.to_string(),
        })?;
        let c = super::Checker {
            source: &format!("parameter `{path}`"),
        };
        let dev = raw.parse(&c)?;
        dev.validate(&format!("parameter `{path}`"))?;
        Ok(dev)
    }
}

/// The per-side paths a path stands for (`stops.both.k` is both sides' `k`).
fn targets(path: &str) -> Vec<String> {
    match path.strip_prefix("stops.both.") {
        Some(k) => vec![format!("stops.upper.{k}"), format!("stops.lower.{k}")],
        None => vec![path.to_string()],
    }
}

/// The value under key `k` of a table, or item `k` (a number) of an array.
fn child<'a>(v: &'a toml::Value, k: &str) -> Option<&'a toml::Value> {
    match v {
        toml::Value::Table(t) => t.get(k),
        toml::Value::Array(a) => a.get(k.parse::<usize>().ok()?),
        _ => None,
    }
}

/// [`child`], mutable.
fn child_mut<'a>(v: &'a mut toml::Value, k: &str) -> Option<&'a mut toml::Value> {
    match v {
        toml::Value::Table(t) => t.get_mut(k),
        toml::Value::Array(a) => a.get_mut(k.parse::<usize>().ok()?),
        _ => None,
    }
}

fn lookup(t: &toml::Table, path: &str) -> Option<f64> {
    let mut parts = path.split('.');
    let mut v = t.get(parts.next()?)?;
    for k in parts {
        v = child(v, k)?;
    }
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Boolean(b) => Some(f64::from(u8::from(*b))),
        _ => None,
    }
}

fn lookup_mut<'a>(t: &'a mut toml::Table, path: &str) -> Option<&'a mut toml::Value> {
    let mut parts = path.split('.');
    let mut v = t.get_mut(parts.next()?)?;
    for k in parts {
        v = child_mut(v, k)?;
    }
    matches!(
        v,
        toml::Value::Float(_) | toml::Value::Integer(_) | toml::Value::Boolean(_)
    )
    .then_some(v)
}

/// The value `value` in the slot's type: an integer for an integer, 0 or 1 for a yes/no.
fn set(slot: &toml::Value, path: &str, value: f64) -> Result<toml::Value, ParamError> {
    let refuse = |range: &str| ParamError::OutOfRange {
        source_name: "parameter".into(),
        field: path.to_string(),
        value,
        range: range.into(),
    };
    Ok(match slot {
        toml::Value::Integer(_) => {
            if value.fract() != 0.0 || !value.is_finite() {
                return Err(refuse("an integer"));
            }
            toml::Value::Integer(value as i64)
        }
        toml::Value::Boolean(_) if value == 0.0 || value == 1.0 => {
            toml::Value::Boolean(value == 1.0)
        }
        toml::Value::Boolean(_) => return Err(refuse("0 (no) or 1 (yes) for a yes/no switch")),
        _ => toml::Value::Float(value),
    })
}
