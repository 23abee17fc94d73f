//! Edits applied in place on kept ones ([`EditBase::with_then`]): the editor's drag step applies
//! the dragged brush to the kept edits' state without copying the part — each vertex a tool
//! writes is noted in an undo log with its values from before, the targets are restated at
//! those vertices only, and everything is put back when the step is done. The targets are
//! those [`EditBase::then`] gives, bit for bit: the same tools run on the same state, and a
//! vertex no tool wrote keeps the kept edits' values.

use nalgebra::Vector3;

use super::{
    apply_in_order, at_edit, phi_not_finite, untangle_noted, Edit, EditBase, EditInput,
    EditOptions, EditResult, State,
};
use crate::Result;

/// One vertex's values of the [`State`] that the brush tools and untangling write.
#[derive(Clone, Copy, Debug)]
pub(crate) struct VertexValues {
    phi: f64,
    designed: Option<f64>,
    g: f64,
    target: Vector3<f64>,
    edit_weight: Option<f64>,
    target_g: f64,
    edit_weight_g: Option<f64>,
    support: bool,
}

impl VertexValues {
    /// Vertex `i`'s values in `st`.
    pub(super) fn of(st: &State, i: usize) -> VertexValues {
        VertexValues {
            phi: st.phi[i],
            designed: st.designed[i],
            g: st.g[i],
            target: st.target[i],
            edit_weight: st.edit_weight[i],
            target_g: st.target_g[i],
            edit_weight_g: st.edit_weight_g[i],
            support: st.support[i],
        }
    }

    /// Puts them back at vertex `i` of `st`.
    fn put(self, st: &mut State, i: usize) {
        st.phi[i] = self.phi;
        st.designed[i] = self.designed;
        st.g[i] = self.g;
        st.target[i] = self.target;
        st.edit_weight[i] = self.edit_weight;
        st.target_g[i] = self.target_g;
        st.edit_weight_g[i] = self.edit_weight_g;
        st.support[i] = self.support;
    }
}

/// One vertex's targets in an [`EditResult`] (see [`State::targets_at`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Targets {
    pub ell: Option<Vector3<f64>>,
    pub weight: f64,
    pub g: Option<f64>,
    pub weight_g: f64,
}

/// One vertex's values of an [`EditResult`] that the brush tools change.
#[derive(Clone, Copy, Debug)]
struct ResultValues {
    phi: f64,
    phi_before: f64,
    targets: Targets,
    support: bool,
}

impl ResultValues {
    fn of(r: &EditResult, i: usize) -> ResultValues {
        ResultValues {
            phi: r.phi[i],
            phi_before: r.phi_before[i],
            targets: Targets {
                ell: r.target_ell[i],
                weight: r.weight[i],
                g: r.target_g[i],
                weight_g: r.weight_g[i],
            },
            support: r.support[i],
        }
    }

    fn put(self, r: &mut EditResult, i: usize) {
        r.phi[i] = self.phi;
        r.phi_before[i] = self.phi_before;
        r.target_ell[i] = self.targets.ell;
        r.weight[i] = self.targets.weight;
        r.target_g[i] = self.targets.g;
        r.weight_g[i] = self.targets.weight_g;
        r.support[i] = self.support;
    }
}

/// What [`EditBase`] keeps to apply edits in place: the kept edits' state and, once asked for,
/// its targets without further edits (made with the options they are kept for).
pub(super) struct Work {
    pub state: State,
    finished: Option<(EditOptions, EditResult)>,
}

impl Work {
    pub fn new(state: State) -> Work {
        Work { state, finished: None }
    }
}

/// A step applied in place: dropping it (at the end of the step, or when it fails or unwinds)
/// puts the state and the kept targets back.
struct InPlace<'a> {
    work: &'a mut Work,
    result_undo: Vec<(u32, ResultValues)>,
}

impl Drop for InPlace<'_> {
    fn drop(&mut self) {
        let w = &mut *self.work;
        if let Some((_, r)) = &mut w.finished {
            for (i, v) in self.result_undo.drain(..).rev() {
                v.put(r, i as usize);
            }
            r.reports.clear();
        }
        if let Some(log) = w.state.undo.take() {
            for (i, v) in log.into_iter().rev() {
                v.put(&mut w.state, i as usize);
            }
        }
    }
}

/// Whether `edit` writes only vertex by vertex (the brush tools that design the grain), so it
/// can be applied in place.
fn in_place(edit: &Edit) -> bool {
    matches!(edit, Edit::Bend(_) | Edit::Expand(_) | Edit::Curve(_))
}

impl EditBase {
    /// [`EditBase::then`] handed to `f` instead of returned, with the vertices whose targets
    /// may differ from the kept edits' alone (ascending; `None`: any vertex may). Bend, expand
    /// and curve edits are applied in place on the kept state (the work is the brush's, not
    /// the part's) and the state is put back when `f` returns; other edits through
    /// [`EditBase::then`]. The targets `f` sees are [`EditBase::then`]'s, bit for bit.
    pub fn with_then<R>(
        &self,
        input: &EditInput,
        more: &[Edit],
        options: &EditOptions,
        f: impl FnOnce(&EditResult, Option<&[u32]>) -> R,
    ) -> Result<R> {
        let mut work = self.work.lock().unwrap_or_else(|e| e.into_inner());
        if !more.iter().all(in_place) || self.finished(&mut work, options).is_err() {
            drop(work);
            let er = self.then(input, more, options)?;
            return Ok(f(&er, None));
        }
        let first = self.reports.len();
        for (j, e) in more.iter().enumerate() {
            e.validate().map_err(|err| at_edit(first + j, e.tool(), err))?;
        }
        let ctx = super::Context::new(input, &self.tables);
        let mut step = InPlace { work: &mut work, result_undo: Vec::new() };
        let st = &mut step.work.state;
        st.undo = Some(Vec::new());
        let mut reports = self.reports.clone();
        reports.extend(apply_in_order(&ctx, st, more, first)?);
        if options.untangle {
            untangle_noted(&ctx, st, &mut reports);
        }
        let mut changed: Vec<u32> =
            st.undo.as_ref().map_or(Vec::new(), |l| l.iter().map(|(i, _)| *i).collect());
        changed.sort_unstable();
        changed.dedup();
        // The errors [`State::finish`] would give: a vertex no tool wrote kept its finite
        // values; the targets first, then the grain, each in vertex order.
        let targets = changed
            .iter()
            .map(|&i| st.targets_at(i as usize, options))
            .collect::<Result<Vec<_>>>()?;
        if let Some(&i) = changed.iter().find(|&&i| !st.phi[i as usize].is_finite()) {
            return Err(phi_not_finite(i as usize));
        }
        let values: Vec<ResultValues> = changed
            .iter()
            .zip(targets)
            .map(|(&i, targets)| {
                let i = i as usize;
                let phi = st.phi[i];
                let phi_before = st.designed[i].unwrap_or(phi);
                ResultValues { phi, phi_before, targets, support: st.support[i] }
            })
            .collect();
        let (_, r) = step.work.finished.as_mut().expect("made above");
        for (&i, v) in changed.iter().zip(values) {
            step.result_undo.push((i, ResultValues::of(r, i as usize)));
            v.put(r, i as usize);
        }
        r.reports = reports;
        Ok(f(r, Some(&changed)))
    }

    /// The kept state's targets without further edits, made once for `options`.
    fn finished(&self, work: &mut Work, options: &EditOptions) -> Result<()> {
        if work.finished.as_ref().is_some_and(|(o, _)| o == options) {
            return Ok(());
        }
        work.finished = None;
        let r = work.state.clone().finish(options, Vec::new())?;
        work.finished = Some((options.clone(), r));
        Ok(())
    }

    /// The kept edits' targets without further edits ([`EditBase::with_then`]'s, for vertices
    /// it does not list), handed to `f`; `None` where they cannot be stated (a target that is
    /// not finite).
    pub fn with_kept<R>(
        &self,
        options: &EditOptions,
        f: impl FnOnce(&EditResult) -> R,
    ) -> Option<R> {
        let mut work = self.work.lock().unwrap_or_else(|e| e.into_inner());
        self.finished(&mut work, options).ok()?;
        work.finished.as_ref().map(|(_, r)| f(r))
    }
}
