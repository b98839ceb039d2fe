"""SecurityAccess key of the canfdi ECU (firmware/uds/canfdi_uds_sec.h).

The tester's copy of canfdi_uds_sec_key_default: with s the level's secret
and all arithmetic mod 2^32,

    k = seed XOR s;  k = rotate_left(k, 11);  k = k * 0x9E3779B1;  key = k XOR (k >> 15)

An ECU built with other secrets (CANFDI_CFG_UDS_SECRET_L1/_L2) or another
key function needs the matching function here: ``canfdi-uds --key-module``
names a module whose ``key(seed: int, level: int) -> int`` replaces this one.
"""
from __future__ import annotations

SECRETS = {1: 0x5A17C0DE, 2: 0x1EE7F00D}
MASK = 0xFFFFFFFF


def key(seed: int, level: int) -> int:
    """The 32-bit key of a 32-bit seed for SecurityAccess level 1 or 2."""
    k = (seed ^ SECRETS.get(level, SECRETS[1])) & MASK
    k = ((k << 11) | (k >> 21)) & MASK
    k = (k * 0x9E3779B1) & MASK
    return k ^ (k >> 15)
