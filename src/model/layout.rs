//! The layout of a model's state: each component's name and unit, which components are a
//! mass's position and velocity, and the names of the model's outputs.

/// One component of the state, or one output: its name and unit, and for an output that is a
/// voltage across a load, the load.
#[derive(Debug, Clone, PartialEq)]
pub struct Slot {
    /// Name, e.g. `"x"`, `"v"`, `"s1"`, `"vs"`.
    pub name: String,
    /// Unit, e.g. `"m"`, `"m/s"`, `"C"`, `"V"`.
    pub unit: String,
    /// The load an output voltage is across, if any.
    pub load: Option<Load>,
}

/// The load an output voltage `V` is across.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Load {
    /// A resistor (ohm): it takes `V^2 / R`.
    Resistor(f64),
    /// A battery of EMF `V_b` behind a resistance (V, ohm): it takes `V (V - V_b) / R`.
    Battery(f64, f64),
}

impl Load {
    /// The mean power the load takes from a voltage of the given mean and mean square (W).
    pub fn mean_power(&self, mean_v: f64, mean_square_v2: f64) -> f64 {
        match *self {
            Load::Resistor(r) => mean_square_v2 / r,
            Load::Battery(vb, r) => (mean_square_v2 - vb * mean_v) / r,
        }
    }
}

/// Most outputs a model may have.
pub const MAX_OUTPUTS: usize = 8;

/// The layout of a model's state (see the module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    /// The state's components, in order.
    pub components: Vec<Slot>,
    /// For each mass, the indices of its position and velocity.
    pub masses: Vec<(usize, usize)>,
    /// The model's named outputs ([`super::Model::outputs`]).
    pub outputs: Vec<Slot>,
    /// The outputs the model holds at zero whatever its state (the loads of a transducer it
    /// does not have), by index into `outputs`: named, so that tables keep their columns, but
    /// a record keeps no samples of them.
    pub zero_outputs: Vec<usize>,
}

impl Layout {
    /// A layout of the named components `(name, unit)` whose first two are one mass's
    /// position and velocity, with no outputs.
    pub fn new(components: &[(&str, &str)]) -> Self {
        Self {
            components: components
                .iter()
                .map(|(n, u)| Slot {
                    name: n.to_string(),
                    unit: u.to_string(),
                    load: None,
                })
                .collect(),
            masses: vec![(0, 1)],
            outputs: Vec::new(),
            zero_outputs: Vec::new(),
        }
    }

    /// The same layout with the named outputs `(name, unit, load)`.
    #[must_use]
    pub fn with_outputs(mut self, outputs: &[(&str, &str, Option<Load>)]) -> Self {
        self.outputs = outputs
            .iter()
            .map(|(n, u, l)| Slot {
                name: n.to_string(),
                unit: u.to_string(),
                load: *l,
            })
            .collect();
        self
    }

    /// The name of mass `k`: its position's component `x_<name>` without the prefix. `None`
    /// where the layout has no such mass or its position is not named after a mass (the one
    /// mass of a one-mass model, whose position is `x`).
    pub fn mass_name(&self, k: usize) -> Option<&str> {
        let x = self.components.get(self.masses.get(k)?.0)?.name.as_str();
        x.strip_prefix("x_")
    }

    /// The index of the component named `name`.
    pub fn component(&self, name: &str) -> Option<usize> {
        self.components.iter().position(|s| s.name == name)
    }

    /// The mean power the outputs' loads take over a span of `duration` (s), from the
    /// integrals over it of each output's square and of itself (W). Outputs across one
    /// resistor are summed before the division (as the paper's two loads of equal resistance
    /// always were), so that their power rounds as `(a + b) / T / R`.
    pub fn load_power(&self, squares: &[f64], integrals: &[f64], duration: f64) -> f64 {
        let mut p = 0.0;
        let mut shared: Option<(f64, f64)> = None;
        for (i, slot) in self.outputs.iter().enumerate() {
            match slot.load {
                Some(Load::Resistor(r)) => match &mut shared {
                    Some((r0, sum)) if *r0 == r => *sum += squares[i],
                    None => shared = Some((r, squares[i])),
                    Some(_) => p += squares[i] / duration / r,
                },
                Some(l) => p += l.mean_power(integrals[i] / duration, squares[i] / duration),
                None => {}
            }
        }
        if let Some((r, sum)) = shared {
            p += sum / duration / r;
        }
        p
    }

    /// Whether the model holds output `i` at zero (see [`Layout::zero_outputs`]).
    pub fn held_at_zero(&self, i: usize) -> bool {
        self.zero_outputs.contains(&i)
    }

    /// The index of the output named `name`.
    pub fn output(&self, name: &str) -> Option<usize> {
        self.outputs.iter().position(|s| s.name == name)
    }
}
