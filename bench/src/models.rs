//! Generated `.som` models at scale, for timing `leeway check` and for the
//! fuzz driver (`fuzz-check`): many states, many media, wide and long
//! equations. Every generator is deterministic in its arguments.

/// `n` states `der x_i = A_i*x_i + D_i*|x_i| + B_i*t_i`: plain moduli
/// (pointwise signs), or relative to one unmeasured current (one fixed sign
/// argument per state) when `medium` is set.
pub fn many_states(n: usize, medium: bool) -> String {
    let states: Vec<String> = (0..n).map(|i| format!("x{i}")).collect();
    let inputs: Vec<String> = (0..n).map(|i| format!("t{i}")).collect();
    let mut s = format!(
        "model States {{\n    step 0.1\n    state {}\n    input {}\n",
        states.join(", "),
        inputs.join(", ")
    );
    if medium {
        let comps: Vec<String> = (0..n).map(|i| format!("x{i}: c{i}")).collect();
        s += &format!(
            "    disturbance current unmeasured body({})\n    water = relative(current)\n",
            comps.join(", ")
        );
    }
    for i in 0..n {
        let x = if medium {
            format!("water.x{i}")
        } else {
            format!("x{i}")
        };
        s += &format!("    der x{i} = A{i}*{x} + D{i}*|{x}| + B{i}*t{i}\n");
    }
    s + "}\n"
}

/// The ship of the paper (surge, sway, yaw; a heading) under `n` media:
/// `unmeasured` of them unmeasured currents, the others measured winds, each
/// seen through one relative velocity with the ship's quadratic drag terms
/// in every equation, so that every medium shares its state-dependent terms
/// with every other (`common-state-term`).
pub fn many_media(n: usize, unmeasured: usize) -> String {
    let mut s = String::from(
        "model Media {\n    step 0.1\n    state u, v, r\n    input tau1, tau2, tau3\n    heading psi integrates r\n",
    );
    for i in 0..n {
        let kind = if i < unmeasured {
            "unmeasured"
        } else {
            "measured"
        };
        s += &format!("    disturbance d{i} {kind} earth(n{i}, e{i})\n    m{i} = relative(d{i})\n");
    }
    let sum = |f: &dyn Fn(usize) -> String| -> String {
        (0..n).map(|i| format!(" + {}", f(i))).collect::<String>()
    };
    s += &format!(
        "    der u = X_u*u + X_tau*tau1{}\n",
        sum(&|i| format!("U{i}*m{i}.u*|m{i}.u|"))
    );
    s += &format!(
        "    der v = Y_v*v + Y_tau*tau2{}\n",
        sum(&|i| format!("V{i}*m{i}.v*|m{i}.v|"))
    );
    s += &format!(
        "    der r = N_r*r + N_tau*tau3{}\n",
        sum(&|i| format!("R{i}*m{i}.u*|m{i}.v|"))
    );
    s + "}\n"
}

/// One state whose equation has `n` distinct parameters each multiplying the
/// same input-only term: `n − 1` `common-input-term` errors and one long
/// unidentifiable combination.
pub fn wide_common(n: usize) -> String {
    let terms: Vec<String> = (0..n).map(|i| format!("P{i}*t")).collect();
    format!(
        "model Wide {{\n    state u\n    input t\n    der u = A*u + {}\n}}\n",
        terms.join(" + ")
    )
}

/// `n` parameters that are constant terms in one equation (all enter only as
/// their sum): one `unidentifiable-combination` naming them all.
pub fn many_constants(n: usize) -> String {
    let terms: Vec<String> = (0..n).map(|i| format!("C{i}")).collect();
    format!(
        "model Constants {{\n    state u\n    input t\n    der u = A*u + B*t + {}\n}}\n",
        terms.join(" + ")
    )
}

/// `state u` repeated `n` times on one line: `n − 1` duplicate declarations
/// pointing into one source line.
pub fn repeated_declarations(n: usize) -> String {
    format!("model M {{ {} der u = X*u }}\n", "state u ".repeat(n))
}
