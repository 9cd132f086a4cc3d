"""The one face every twin shows (docs/architecture.md).

:mod:`.face` the Device protocol and its values; :mod:`.registry` the kinds of
device; :mod:`.schema` the plant schema; :mod:`.context` the build context; one
adapter file per device kind (:mod:`.aem811`, :mod:`.dem24`, :mod:`.scm`, :mod:`.tes`).
"""
