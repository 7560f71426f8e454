//! Right-hand sides in canonical spacing: `a*b/c`, `a + b - c`, `|x|`, `-x`,
//! `(a + b)`. The tree comes from the parser, whose `Paren` nodes say where
//! the author's parentheses were, so printing without adding any gives the
//! same tree back.

use leeway_grammar::{BinOp, Expr};

/// `e` in canonical spacing. A new kind of factor (a marker on a
/// parameter, say) is one more arm here.
pub(crate) fn text(e: &Expr) -> String {
    let mut out = String::new();
    write(e, &mut out);
    out
}

fn write(e: &Expr, out: &mut String) {
    match e {
        Expr::Number(n) => out.push_str(&n.text),
        Expr::Path(p) => {
            // A candidate's `?` is not part of `Path::text`.
            if p.candidate {
                out.push('?');
            }
            out.push_str(&p.text());
        }
        Expr::Abs(x, _) => {
            out.push('|');
            write(x, out);
            out.push('|');
        }
        Expr::Neg(x, _) => {
            out.push('-');
            write(x, out);
        }
        Expr::Paren(x, _) => {
            out.push('(');
            write(x, out);
            out.push(')');
        }
        Expr::Binary { op, lhs, rhs, .. } => {
            write(lhs, out);
            out.push_str(op_text(*op));
            write(rhs, out);
        }
    }
}

fn op_text(op: BinOp) -> &'static str {
    match op {
        BinOp::Add => " + ",
        BinOp::Sub => " - ",
        BinOp::Mul => "*",
        BinOp::Div => "/",
    }
}

/// The terms of a sum as written at its top level: the first with no
/// operator, the others with their `+` or `-`. Sums inside `( )` or `| |`
/// are one term.
pub(crate) fn terms(e: &Expr) -> Vec<(Option<BinOp>, &Expr)> {
    match e {
        Expr::Binary {
            op: op @ (BinOp::Add | BinOp::Sub),
            lhs,
            rhs,
            ..
        } => {
            let mut t = terms(lhs);
            t.push((Some(*op), rhs));
            t
        }
        _ => vec![(None, e)],
    }
}
