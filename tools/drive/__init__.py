"""Drive profiles: fault-free driving for the plants from a published drive cycle.

Modules:
  wltc      the WLTC class 3 speed trace (UNECE GTR 15) from the wltp package, and its micro-trips
  generate  the mapping to motor speed, load, throttle angle and supplies; the profile CSV
            (console command canfdi-drive-profile; docs/driving.md)
"""
