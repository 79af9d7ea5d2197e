//! Typed errors of the cloth physics. Every variant names the element (face, hinge,
//! vertex, contact) and says what was expected, so a caller can point at the bad input.

/// What went wrong building or evaluating an energy, or running the simulator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A position, gradient or matrix buffer has the wrong number of vertices.
    #[error("{what}: expected {expected} vertices, got {got}")]
    VertexCount {
        /// Which buffer (`positions`, `gradient`, `hessian`, `masses`, ...).
        what: &'static str,
        /// The energy's vertex count.
        expected: usize,
        /// The buffer's length.
        got: usize,
    },
    /// A per-element parameter list has the wrong length.
    #[error("{what}: expected {expected} values (one per {element}), got {got}")]
    ParameterCount {
        /// Which parameter (`mu`, `lambda`, `density`, `bending stiffness`, ...).
        what: &'static str,
        /// `face`, `hinge` or `vertex`.
        element: &'static str,
        /// Number of elements.
        expected: usize,
        /// Number of values given.
        got: usize,
    },
    /// A vertex index is outside the mesh.
    #[error(
        "{element} {index}: vertex {vertex} is out of range (the mesh has {vertex_count} vertices)"
    )]
    VertexOutOfRange {
        /// `face`, `hinge` or `contact`.
        element: &'static str,
        /// The element's index.
        index: usize,
        /// The offending vertex index.
        vertex: u32,
        /// The mesh's vertex count.
        vertex_count: usize,
    },
    /// A button pair names a vertex outside the garment or the same vertex twice.
    #[error(
        "button pair {index} ({a}, {b}): expected two different vertices below {vertex_count}"
    )]
    ButtonPair {
        /// The pair's index.
        index: usize,
        /// Its first vertex.
        a: u32,
        /// Its second vertex.
        b: u32,
        /// The garment's vertex count.
        vertex_count: usize,
    },
    /// A rest triangle (from positions or UVs) has (almost) no area, so it has no rest
    /// frame; remove it or fix the rest shape.
    #[error("face {face}: degenerate rest triangle (area {area:e}); remove or repair it")]
    DegenerateTriangle {
        /// The face.
        face: usize,
        /// Its rest area.
        area: f64,
    },
    /// A material or energy parameter is NaN, infinite, or outside its valid range.
    #[error("{what} = {value}: {expected}")]
    InvalidParameter {
        /// The parameter (with the element index where there is one).
        what: String,
        /// The value given.
        value: f64,
        /// The valid range, in words.
        expected: &'static str,
    },
    /// An input vector (position, normal, UV) is not finite or has zero length where a
    /// direction is needed.
    #[error("{what}: {message}")]
    InvalidVector {
        /// The vector (with the element index).
        what: String,
        /// What is wrong.
        message: &'static str,
    },
    /// A Hessian block was scattered outside the matrix's sparsity pattern: the matrix
    /// was built for another set of energies.
    #[error("Hessian block ({row}, {col}) is not in the sparsity pattern; build the matrix with IncrementalPotential::hessian_pattern of the same potential and Hessian kind")]
    NotInPattern {
        /// Block row (vertex).
        row: usize,
        /// Block column (vertex).
        col: usize,
    },
    /// A material preset name is unknown.
    #[error("unknown material {name:?}; expected one of: {known}")]
    UnknownMaterial {
        /// The name asked for.
        name: String,
        /// The preset names, comma-separated.
        known: String,
    },
    /// The body surface could not be built or updated (empty mesh, bad index, a
    /// non-finite vertex, a refit with another vertex count).
    #[error("the body surface could not be built or updated")]
    BodySurface(#[from] weft_body::query::QueryError),
    /// Every garment vertex is far from the body: a garment in another frame, in
    /// centimetres, or moved away.
    #[error("the garment's nearest vertex is {gap:.3} m from the body, more than {max} m; expected a garment on the body in its rest pose (metres, the body's frame), as `weft garment generate` or `weft garment prepare` write them")]
    OffBody {
        /// The smallest distance of a garment vertex to the body surface (m).
        gap: f64,
        /// [`crate::body::MAX_GARMENT_GAP`].
        max: f64,
    },
    /// The simulation produced non-finite positions or did not converge.
    #[error("step diverged: {message}")]
    Diverged {
        /// What was detected.
        message: String,
    },
}

/// Checks that a buffer holds exactly `expected` vertices.
pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), SimError> {
    if expected == got {
        Ok(())
    } else {
        Err(SimError::VertexCount {
            what,
            expected,
            got,
        })
    }
}

/// The buffer an [`Energy`](crate::Energy) method writes besides reading positions, for
/// [`check_eval`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum Output {
    /// `value`: nothing but the positions.
    Value,
    /// `add_gradient`: a gradient of this many vertices.
    Gradient(usize),
    /// `add_hessian`: a block matrix of this many block rows.
    Hessian(usize),
}

/// The prologue of every [`Energy`](crate::Energy) method: the positions and the output
/// hold the energy's `vertex_count` vertices each.
pub(crate) fn check_eval(
    vertex_count: usize,
    x: &[[f64; 3]],
    output: Output,
) -> Result<(), SimError> {
    check_len("positions", vertex_count, x.len())?;
    match output {
        Output::Value => Ok(()),
        Output::Gradient(n) => check_len("gradient", vertex_count, n),
        Output::Hessian(n) => check_len("hessian", vertex_count, n),
    }
}

/// Checks that a per-element list has one value per element.
pub(crate) fn check_count(
    what: &'static str,
    element: &'static str,
    expected: usize,
    got: usize,
) -> Result<(), SimError> {
    if expected == got {
        Ok(())
    } else {
        Err(SimError::ParameterCount {
            what,
            element,
            expected,
            got,
        })
    }
}

/// Checks that `value` is finite and `>= 0` (`> 0` when `strict`).
pub(crate) fn check_nonneg(
    what: impl Fn() -> String,
    value: f64,
    strict: bool,
) -> Result<(), SimError> {
    let ok = value.is_finite() && if strict { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(SimError::InvalidParameter {
            what: what(),
            value,
            expected: if strict {
                "expected a finite value > 0"
            } else {
                "expected a finite value >= 0"
            },
        })
    }
}

/// Checks that a vertex index is inside the mesh.
pub(crate) fn check_vertex(
    element: &'static str,
    index: usize,
    vertex: u32,
    vertex_count: usize,
) -> Result<(), SimError> {
    if (vertex as usize) < vertex_count {
        Ok(())
    } else {
        Err(SimError::VertexOutOfRange {
            element,
            index,
            vertex,
            vertex_count,
        })
    }
}
