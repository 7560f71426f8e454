//! The sparse echelon form (used by every rank decision) equals the dense
//! one on random matrices, including ones whose entries overflow the `i128`
//! fast path: the reduced row echelon form is unique, so pivots and
//! combinations must agree exactly.

use leeway_structure::exact::{Q, SparseRow, echelon, echelon_sparse};
use num_bigint::BigInt;
use proptest::prelude::*;

fn q(n: i64, d: i64) -> Q {
    Q::new(BigInt::from(n), BigInt::from(d))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn sparse_echelon_equals_dense(
        n_cols in 1usize..9,
        rows in proptest::collection::vec(
            proptest::collection::vec((-3i64..=3, 1i64..=4, any::<bool>()), 8),
            0..10
        ),
        big in any::<bool>(),
    ) {
        let dense: Vec<Vec<Q>> = rows
            .iter()
            .map(|r| {
                r.iter()
                    .take(n_cols)
                    .map(|&(n, d, sparse)| {
                        if sparse && n % 2 == 0 {
                            q(0, 1)
                        } else if big {
                            // Entries near 2^62 overflow i128 products.
                            Q::new(BigInt::from(n) * BigInt::from(1i64 << 60) + n, BigInt::from(d))
                        } else {
                            q(n, d)
                        }
                    })
                    .collect()
            })
            .collect();
        let sparse: Vec<SparseRow> = dense
            .iter()
            .map(|r| {
                r.iter()
                    .enumerate()
                    .filter(|(_, x)| **x != q(0, 1))
                    .map(|(j, x)| (j, x.clone()))
                    .collect()
            })
            .collect();
        prop_assert_eq!(echelon_sparse(&sparse, n_cols), echelon(&dense, n_cols));
    }
}
