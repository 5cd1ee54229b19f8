//! The instances of arrays of packages (`package P[i in a .. b]`): each has its own values for
//! the package's names, kept per scope, instance and name. How they are made and looked up is
//! in `arrays.rs`.

use rustc_hash::FxHashMap;

use crate::check::scope::ScopeId;
use crate::syntax::ast::Name;

/// An instance of an array of packages; `ROOT` stands for the files and plain packages.
pub(super) type InstanceId = u32;
pub(super) const ROOT: InstanceId = 0;

pub(super) struct Instance {
    pub(super) package: Name,
    pub(super) scope: ScopeId,
    /// The instance of the enclosing array, or `ROOT`.
    pub(super) parent: InstanceId,
    pub(super) index: i64,
}

pub(super) struct Instances {
    pub(super) table: Vec<Instance>,
    pub(super) ids: FxHashMap<(InstanceId, ScopeId, i64), InstanceId>,
    /// Each array's range, by its scope and the instance of the scope around it.
    pub(super) ranges: FxHashMap<(ScopeId, InstanceId), (i64, i64)>,
    /// The instance whose declarations or names are being evaluated.
    pub(super) current: InstanceId,
}

impl Default for Instances {
    fn default() -> Instances {
        let root = Instance {
            package: Name::from(""),
            scope: ScopeId(u32::MAX),
            parent: ROOT,
            index: 0,
        };
        Instances {
            table: vec![root],
            ids: FxHashMap::default(),
            ranges: FxHashMap::default(),
            current: ROOT,
        }
    }
}

impl Instances {
    /// How objects declared in an instance are named: `P[3]:` (`P[3]:Q[1]:` when nested), or
    /// nothing outside arrays.
    pub(super) fn prefix(&self, mut id: InstanceId) -> String {
        let mut parts = Vec::new();
        while id != ROOT {
            let instance = &self.table[id as usize];
            parts.push(format!("{}[{}]:", instance.package, instance.index));
            id = instance.parent;
        }
        parts.reverse();
        parts.concat()
    }
}
