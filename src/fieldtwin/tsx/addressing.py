"""PL7 object names, now in the kernel (fieldtwin.objects); this path keeps working."""

from fieldtwin.objects import (
    BITS,
    RACKS,
    SLOTS,
    TSX_47_20_INTELLIGENT_SLOTS,
    TXT_CHANNELS,
    TXT_MODULE_SYSTEM,
    WORD_INDEXES,
    ObjectKind,
    ObjectRef,
    TxtAddress,
    format_module,
    format_object,
    format_txt_address,
    parse_module,
    parse_object,
    parse_txt_address,
)

__all__ = [
    "BITS",
    "RACKS",
    "SLOTS",
    "TSX_47_20_INTELLIGENT_SLOTS",
    "TXT_CHANNELS",
    "TXT_MODULE_SYSTEM",
    "WORD_INDEXES",
    "ObjectKind",
    "ObjectRef",
    "TxtAddress",
    "format_module",
    "format_object",
    "format_txt_address",
    "parse_module",
    "parse_object",
    "parse_txt_address",
]
