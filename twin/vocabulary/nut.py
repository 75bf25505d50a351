"""The two nuts (Eq. 9.8): its entries in the model's vocabulary (:mod:`twin.layout`)."""

from twin.vocabulary.entries import Component
from twin.vocabulary.entries import entry as _e

DECLARATION = Component("nut", instances=2, states=(
    _e("NUT{n}_POSITION", "m", ("master nut (nut 1, the sled) translation x_n1 (Eq. 9.8)",
                                "slave nut (nut 2) translation x_n2 (Eq. 9.8)")),
    _e("NUT{n}_SPEED", "m/s", ("master nut (nut 1) speed", "slave nut (nut 2) speed")),
    _e("NUT{n}_ANGLE", "rad", ("master nut (nut 1) roll angle on the guides theta_n1",
                               "slave nut (nut 2) roll angle on the guides theta_n2")),
    _e("NUT{n}_ANGULAR_SPEED", "rad/s", ("master nut (nut 1) roll speed", "slave nut (nut 2) roll speed")),
), constants=(
    _e("NUT{n}_MASS", "kg", ("translating mass of the master nut (nut 1) and the sled it carries",
                             "translating mass of the slave nut (nut 2)"),
       ("sled.master_mass", "sled.slave_mass")),
    _e("NUT{n}_GUIDE_FRICTION_SHARE", "1", ("share of the guide friction law the master nut carries (1)",
                                           "share of the guide friction law the slave nut carries")),
), signals=(
    _e("NUT{n}_POSITION", "m", ("master nut (nut 1, the sled) position", "slave nut (nut 2) position")),
    _e("NUT{n}_CONTACT_FORCE", "N", ("axial contact force of the screw on the master nut (nut 1)",
                                     "axial contact force of the screw on the slave nut (nut 2)")),
))
