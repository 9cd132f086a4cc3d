"""TSX SCM 20xy / 21xy / 22xy serial communication modules, character-string mode.

``MODULE_TYPES`` maps each reference of appendix 7.3 to its module class.
"""

from __future__ import annotations

from fieldtwin.tsx.scm.endpoints import MemoryPeer
from fieldtwin.tsx.scm.module import ScmModule
from fieldtwin.tsx.scm.variants import VARIANTS, Adaptor, Variant


def _module_class(variant: Variant) -> type[ScmModule]:
    name = "Scm" + variant.reference.rsplit(" ", 1)[1]
    attrs = {
        "variant": variant,
        "type_name": variant.reference,
        "hardware_codes": frozenset({variant.hardware_code}),
        "version_text": variant.version_text,
        "__module__": __name__,
    }
    return type(name, (ScmModule,), attrs)


MODULE_TYPES: dict[str, type[ScmModule]] = {
    reference: _module_class(variant) for reference, variant in VARIANTS.items()
}

__all__ = ["MODULE_TYPES", "VARIANTS", "Adaptor", "MemoryPeer", "ScmModule", "Variant"]
