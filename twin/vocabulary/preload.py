"""The preload set between the nuts (Secs. 9.2-9.3): its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e
from twin.vocabulary.entries import work as _w

DECLARATION = Component("preload", constants=(
    _e("PRELOAD_STIFFNESS", "N/m", "disc springs in series with the preload load cell"),
    _e("PRELOAD_DAMPING", "N s/m", "preload damping"),
    _e("PRELOAD_COMPRESSION", "m", "spring-set compression at the assembled position"),
    _e("PRELOAD_ORIENTATION", "1", "+1: O configuration (nuts pushed apart), -1: X"),
), signals=(
    _e("PRELOAD_FORCE", "N", "preload force between the nuts"),
), work=(
    _w("PRELOAD", "N", "preload magnitude"),
))
