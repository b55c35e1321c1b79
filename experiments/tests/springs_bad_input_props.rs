//! Property tests of generated suspension files: a `[mechanics.suspension]` table of any form,
//! any keys and any values, with or without stops of any law, either loads or is refused with
//! an error naming its source; nothing panics, and a device that loads has a reference well,
//! builds its model and reports its equilibria without panicking.

use endstop::device::Device;
use endstop::model::Model;
use endstop::physics::harvester::Harvester;
use proptest::prelude::*;
use proptest::sample::select;

/// Values a field may take: ordinary, extreme, zero, negative and non-finite.
fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        (-1e12f64..1e12).prop_map(|v| format!("{v:e}")),
        (-6.0f64..6.0).prop_map(|e| format!("{:e}", 10f64.powf(e))),
        (-6.0f64..6.0).prop_map(|e| format!("{:e}", -(10f64.powf(e)))),
        select(vec![
            "0.0", "-0.0", "nan", "inf", "-inf", "1e308", "-1e308", "5e-324", "\"x\"", "true"
        ])
        .prop_map(String::from),
    ]
}

/// The suspension's keys, and two that no form takes.
fn keys() -> Vec<&'static str> {
    let mut k = endstop::device::suspension::COEFFICIENT_KEYS.to_vec();
    k.extend(["well_m", "barrier_j", "stiffness", "form_extra"]);
    k
}

fn suspension() -> impl Strategy<Value = String> {
    (
        select(vec![
            "\"linear\"",
            "\"polynomial\"",
            "\"bistable\"",
            "\"quartic\"",
            "3",
            "",
        ]),
        proptest::collection::vec((select(keys()), value()), 0..6),
    )
        .prop_map(|(form, kv)| {
            let mut s = String::from("[mechanics.suspension]\n");
            if !form.is_empty() {
                s.push_str(&format!("form = {form}\n"));
            }
            let mut seen = std::collections::HashSet::new();
            for (k, v) in kv {
                if seen.insert(k) {
                    s.push_str(&format!("{k} = {v}\n"));
                }
            }
            s
        })
}

fn stops() -> impl Strategy<Value = String> {
    (
        select(vec!["", "both", "upper", "lower"]),
        value(),
        select(vec![
            "law = \"linear\"\nstiffness_n_per_m = 1e4",
            "law = \"restitution\"\ncoefficient = 0.7",
            "law = \"hertz_point\"\nstiffness_n_per_m1p5 = 1e8",
            "law = \"hunt_crossley\"\nstiffness_n_per_m_pow_n = 1e12\nexponent = 3.0\ndamping_s_per_m = 0.1",
        ]),
    )
        .prop_map(|(side, gap, law)| {
            if side.is_empty() {
                String::new()
            } else {
                format!("[stops.{side}]\ngap_m = {gap}\n{law}\n")
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, .. ProptestConfig::default() })]

    #[test]
    fn generated_suspension_files_never_panic(
        susp in suspension(),
        stop in stops(),
        stiffness in proptest::option::of(value()),
    ) {
        let mut text = String::from(
            "name = \"gen\"\nparams = \"test\"\ndescription = \"generated\"\n\
             [transducer]\nkind = \"none\"\n[mechanics]\nmass_kg = 1e-3\ndamping_n_s_per_m = 0.02\n",
        );
        if let Some(k) = stiffness {
            text.push_str(&format!("stiffness_n_per_m = {k}\n"));
        }
        text.push_str(&susp);
        text.push_str(&stop);
        match Device::from_toml_str(&text, "generated.toml") {
            Ok(d) => {
                let k = d.mechanics.stiffness_n_per_m;
                prop_assert!(k.is_finite() && k > 0.0, "{text}\nloaded with k = {k}");
                let _ = endstop::physics::statics::equilibria(&d);
                let h = Harvester::<4>::new(&d);
                prop_assert!(h.is_ok(), "{text}\n{:?}", h.err());
                if let Ok(h) = h {
                    prop_assert!(h.scales().iter().all(|s| s.is_finite()), "{text}");
                }
            }
            Err(e) => prop_assert!(e.to_string().contains("generated.toml"), "{e}"),
        }
    }
}
