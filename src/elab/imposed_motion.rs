//! The motions a program imposes in time: a `drive` (`drive crank.q = 2 * pi * time`), a
//! position drive (`drive position(nacelle) = [x, y, z]`, elaborated here) or `time` in a dof
//! chain (a rheonomic joint, `kinematics::rheonomic`). The studies that read a
//! mechanism as free coordinates (the symbolic equations, `statics`, `eval`, `kinematics`)
//! refuse them at the place the program imposes one, rather than answer for another mechanism.

use super::elaborator::{internal, Elaborator};
use super::eval::Locals;
use super::mechanism::{Mechanism, PositionDrive};
use super::operations::{as_frame, as_vector};
use super::value::Elementary;
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::DriveDecl;

type Result<T> = std::result::Result<T, Diagnostic>;

impl Elaborator<'_, '_> {
    /// `drive position(F) = law`: the frame and the three laws (the checker made sure of
    /// their types).
    pub(super) fn position_drive(&mut self, decl: &DriveDecl, locals: &mut Locals) -> Result<()> {
        let Some(written) = decl.position_target() else {
            return Err(internal("a position drive without a frame"));
        };
        let frame = self
            .expr(written, locals)
            .and_then(|v| as_frame(v, written.span))?;
        let law = self
            .expr(&decl.value, locals)
            .and_then(|v| as_vector(v, decl.value.span))?;
        let count = self.mechanism.position_drives.len();
        self.mechanism.position_drives.push(PositionDrive {
            frame,
            name: written
                .as_path()
                .unwrap_or_else(|| format!("position_drive{}", count + 1)),
            law,
            span: decl.target.span,
            law_span: decl.value.span,
        });
        Ok(())
    }
}

/// Where a program imposes a motion in time, and what the label there says.
#[derive(Clone, Debug)]
pub struct ImposedMotion {
    pub span: Span,
    /// `the drive of `crank``, `the dof chain of `swing` depends on the time`.
    pub label: String,
}

/// The first motion the program imposes in time: its first drive, else the first join whose
/// dof chain uses the time.
pub fn first_imposed_motion(mechanism: &Mechanism) -> Option<ImposedMotion> {
    if let Some(drive) = mechanism.drives.first() {
        return Some(ImposedMotion {
            span: drive.span,
            label: format!(
                "this drive imposes the motion of `{}`",
                mechanism.join_name(drive.join)
            ),
        });
    }
    if let Some(drive) = mechanism.position_drives.first() {
        return Some(ImposedMotion {
            span: drive.span,
            label: format!("this drive imposes the position of `{}`", drive.name),
        });
    }
    let uses_time = |step: &Elementary| match step {
        Elementary::Translation(v) => v.iter().any(|s| s.uses_time()),
        Elementary::Rotation { angle, axis } => {
            angle.uses_time() || axis.iter().any(|s| s.uses_time())
        }
    };
    let id = (0..mechanism.joins.len() as u32)
        .map(super::value::JoinId)
        .find(|&id| {
            let link = mechanism.link(mechanism.join(id).link);
            link.dofs.iter().flat_map(|d| d.0.iter()).any(uses_time)
        })?;
    let join = mechanism.join(id);
    Some(ImposedMotion {
        span: mechanism.link(join.link).span,
        label: format!(
            "the dof chain of `{}` depends on the time",
            mechanism.join_name(id)
        ),
    })
}

/// E0491: `subject` (a command, "`lsdc statics`") does not handle the motions the program
/// imposes in time; `help` says what to run instead. `None` when the program imposes none.
pub fn refused_by(mechanism: &Mechanism, subject: &str, help: &str) -> Option<Diagnostic> {
    let motion = first_imposed_motion(mechanism)?;
    Some(
        Diagnostic::error(
            "E0491",
            format!(
                "{subject} does not handle motions imposed in time (`drive`, `time` in a dof chain), and this program imposes one"
            ),
        )
        .primary(motion.span, motion.label)
        .help(help.to_string()),
    )
}
