//! The interface laws of a cell and which element takes which: the ITZ's law on the ITZ
//! elements, and with cracks through the paste the paste's on those. Every element's
//! points carry the same number of history values (the laws must agree on it), so the
//! flat history keeps one stride and a host's `STATEV` one size per scene.

use std::sync::Arc;

use crate::error::{Error, Result};
use crate::interface::InterfaceLaw;
use crate::mesh::InterfaceKind;

/// The laws of a cell's interface elements.
#[derive(Clone, Debug)]
pub struct InterfaceLaws {
    itz: Arc<dyn InterfaceLaw>,
    paste: Option<Arc<dyn InterfaceLaw>>,
    kinds: Arc<[InterfaceKind]>,
}

impl InterfaceLaws {
    /// `itz` on the ITZ elements, `paste` on the paste's (required when `kinds` has any).
    pub fn new(
        itz: Arc<dyn InterfaceLaw>,
        paste: Option<Arc<dyn InterfaceLaw>>,
        kinds: Vec<InterfaceKind>,
    ) -> Result<Self> {
        let has_paste = kinds.contains(&InterfaceKind::Paste);
        match &paste {
            None if has_paste => {
                return Err(Error::Mesh(
                    "the mesh has paste interface elements and the scene no paste crack law".into(),
                ))
            }
            Some(p) if p.history_len() != itz.history_len() => {
                return Err(Error::Mesh(format!(
                    "the paste's crack law keeps {} history values a point and the ITZ's {}: \
                     the laws of one cell must agree",
                    p.history_len(),
                    itz.history_len()
                )))
            }
            _ => {}
        }
        Ok(InterfaceLaws {
            itz,
            paste,
            kinds: kinds.into(),
        })
    }

    /// The law of interface element `element`.
    #[inline]
    pub fn of(&self, element: usize) -> &dyn InterfaceLaw {
        match (self.kinds[element], &self.paste) {
            (InterfaceKind::Paste, Some(paste)) => paste.as_ref(),
            _ => self.itz.as_ref(),
        }
    }

    /// These laws with the paste's softening stretched `scale` times
    /// ([`InterfaceLaw::regularized`]), the ITZ's law unchanged: the ITZ's law softens from
    /// its first opening, so most of its softening happens before the cell's peak, as
    /// diffuse debonding that a crack band must not scale (stretching it too raises the
    /// cell's strength, `docs/fracture.md`); the paste's cracks open past the peak, where
    /// the cell localizes.
    pub fn regularized(&self, scale: f64) -> InterfaceLaws {
        let stretch = |law: &Arc<dyn InterfaceLaw>| law.regularized(scale).unwrap_or(law.clone());
        InterfaceLaws {
            itz: self.itz.clone(),
            paste: self.paste.as_ref().map(stretch),
            kinds: self.kinds.clone(),
        }
    }

    /// The ITZ's law.
    pub fn itz(&self) -> &dyn InterfaceLaw {
        self.itz.as_ref()
    }

    /// The paste's crack law, if the cell has one.
    pub fn paste(&self) -> Option<&dyn InterfaceLaw> {
        self.paste.as_deref()
    }

    /// History values per quadrature point (the same for every law of the cell).
    pub fn history_len(&self) -> usize {
        self.itz.history_len()
    }

    /// Whether some law of the cell holds a contact status.
    pub fn has_contact_status(&self) -> bool {
        self.itz.has_contact_status() || self.paste.as_ref().is_some_and(|p| p.has_contact_status())
    }

    /// Whether a whole interface history (`points_per_interface` points an element) is
    /// admissible for the elements' laws (a checkpoint's, a `STATEV`'s).
    pub fn history_is_valid(&self, history: &[f64], points_per_interface: usize) -> bool {
        let per_element = points_per_interface * self.history_len();
        per_element == 0
            || history
                .chunks(per_element)
                .enumerate()
                .all(|(e, h)| e < self.kinds.len() && self.of(e).history_is_valid(h))
    }

    /// The kind of each element.
    pub fn kinds(&self) -> &[InterfaceKind] {
        &self.kinds
    }
}
