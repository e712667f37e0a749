"""Security: a CA, certificates and Zenoh access-control configuration for one vehicle's bus."""

from roadgaze.security.bundle import (
    client_config,
    daemon_config,
    init_bundle,
    router_config,
)
from roadgaze.security.certificates import CertificateAuthority, Issued
from roadgaze.security.policy import PERMISSIONS, access_control, downsampling, low_pass_filter

__all__ = [
    "PERMISSIONS",
    "CertificateAuthority",
    "Issued",
    "access_control",
    "client_config",
    "daemon_config",
    "downsampling",
    "init_bundle",
    "low_pass_filter",
    "router_config",
]
