"""`roadgaze security init`: a CA, certificates and Zenoh configuration files for one vehicle.

Layout of DIR (keys are 0600; `ca/ca.key` signs, keep it off the vehicle):

    ca/ca.pem ca/ca.key
    router/   cert.pem key.pem ca.pem zenoh.json5   `zenohd -c router/zenoh.json5`
    daemon/   ...                                   `roadgaze run --zenoh-config daemon/zenoh.json5`
    speed/    ...                                   the speed provider's session
    consumer-NAME/ ...                              `roadgaze listen --zenoh-config ...`

Every role folder holds its own copy of `ca.pem`, so it can be mounted alone; `path_root` writes
the paths as seen where the folders are mounted (e.g. `/etc/roadgaze/zenoh` in a container).
Only TLS with client certificates (mutual TLS) is accepted by the router; shared memory is off
everywhere (it would carry payloads past the size limits).
"""

from __future__ import annotations

import ipaddress
import json
import os
import re
from pathlib import Path
from typing import Any

from roadgaze.errors import ConfigError
from roadgaze.security.certificates import CertificateAuthority, Issued
from roadgaze.security.policy import VSS_KEYS, access_control, downsampling, low_pass_filter
from roadgaze.transport.keys import Keys

CONSUMER_NAME = re.compile(r"[A-Za-z0-9_-]{1,32}")
MAX_MESSAGE_BYTES = 1 << 20
"""`transport/link/rx/max_message_size` everywhere: a larger (fragmented) message is dropped."""
ROUTER_LEASE_MS = 3000
"""The router's lease: its clients notice a hung router (no socket error) in about 2.3 s."""
RETRY = {"period_init_ms": 250, "period_max_ms": 1000, "period_increase_factor": 2}


def _tls(folder: Path, *, server: bool) -> dict[str, Any]:
    side = "listen" if server else "connect"
    return {
        "root_ca_certificate": str(folder / "ca.pem"),
        f"{side}_certificate": str(folder / "cert.pem"),
        f"{side}_private_key": str(folder / "key.pem"),
        "enable_mtls": True,
        "verify_name_on_connect": True,
        "close_link_on_expiration": True,
    }


def _transport(folder: Path, *, server: bool) -> dict[str, Any]:
    link: dict[str, Any] = {
        "protocols": ["tls"],
        "tls": _tls(folder, server=server),
        "rx": {"max_message_size": MAX_MESSAGE_BYTES},
    }
    if server:
        link["tx"] = {"lease": ROUTER_LEASE_MS}
    return {"link": link, "shared_memory": {"enabled": False}}


def router_config(
    folder: Path,
    listen: str,
    keys: Keys,
    common_names: dict[str, list[str]],
    vss_keys: str = VSS_KEYS,
) -> dict[str, Any]:
    return {
        "mode": "router",
        "listen": {"endpoints": [listen]},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": _transport(folder, server=True),
        "access_control": access_control(keys, common_names, vss_keys),
        "low_pass_filter": low_pass_filter(keys, vss_keys),
        "downsampling": downsampling(keys),
    }


def daemon_config(folder: Path, endpoint: str) -> dict[str, Any]:
    """A peer (it opens without the router; alerts wait in the publisher's cache) that listens
    nowhere and does not gossip: its only link is the router, where access control applies."""
    return {
        "mode": "peer",
        "connect": {"endpoints": [endpoint], "retry": RETRY},
        "listen": {"endpoints": []},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": _transport(folder, server=False),
    }


def client_config(folder: Path, endpoint: str) -> dict[str, Any]:
    """The speed provider and the consumers: clients of the router."""
    return {
        "mode": "client",
        "connect": {"endpoints": [endpoint], "retry": RETRY},
        "scouting": {"multicast": {"enabled": False}},
        "transport": _transport(folder, server=False),
    }


def _host_names(endpoint: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(DNS names, IP addresses) the router's certificate must carry for `endpoint`."""
    host = endpoint.partition("/")[2].rpartition(":")[0].strip("[]")
    dns, ips = {"localhost"}, {"127.0.0.1"}
    try:
        ipaddress.ip_address(host)
        ips.add(host)
    except ValueError:
        dns.add(host)
    return tuple(sorted(dns)), tuple(sorted(ips))


HOST_NAME = re.compile(
    r"[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*"
)


def check_tls_endpoint(option: str, value: str) -> None:
    """Raise ConfigError unless `value` is `tls/HOST:PORT` a router can listen on and clients
    reach: HOST a host name, an IPv4 address or an IPv6 address in brackets, PORT 1-65535."""
    usage = f"{option} must be tls/HOST:PORT (an IPv6 address in brackets: tls/[::1]:7447)"
    protocol, _, host_port = value.partition("/")
    host, _, port = host_port.rpartition(":")
    if protocol != "tls" or not host or not port:
        raise ConfigError(f"{usage}, found {value[:80]!r}")
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise ConfigError(f"{option}: port must be 1-65535, found {port[:20]!r} in {value[:80]!r}")
    if host.startswith("[") or host.endswith("]") or ":" in host:
        inner = host[1:-1] if host.startswith("[") and host.endswith("]") else None
        try:
            if inner is None or ipaddress.ip_address(inner).version != 6:
                raise ValueError(host)
        except ValueError:
            raise ConfigError(
                f"{usage}: {host[:60]!r} is not an IPv6 address in brackets"
            ) from None
        return
    try:
        ipaddress.ip_address(host)
        return
    except ValueError:
        pass
    if len(host) > 253 or not HOST_NAME.fullmatch(host):
        raise ConfigError(f"{usage}: {host[:60]!r} is not a host name or an IP address")


def _write(path: Path, data: bytes, private: bool = False) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)  # a new file gets the mode below
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600 if private else 0o644)
    with os.fdopen(descriptor, "wb") as handle:
        handle.write(data)


def _check(out_dir: Path, consumers: list[str], endpoint: str, listen: str, force: bool) -> None:
    for name in consumers:
        if not CONSUMER_NAME.fullmatch(name):
            raise ConfigError(f"consumer name must be 1-32 of [A-Za-z0-9_-], found {name[:40]!r}")
    if len(set(consumers)) != len(consumers):
        raise ConfigError("consumer names must be distinct")
    for option, value in (("--endpoint", endpoint), ("--listen", listen)):
        check_tls_endpoint(option, value)
    if out_dir.exists() and not out_dir.is_dir():
        raise ConfigError(f"{out_dir} exists and is not a folder")
    if out_dir.is_dir() and any(out_dir.iterdir()) and not force:
        raise ConfigError(
            f"{out_dir} is not empty: a new CA would invalidate the certificates in use; "
            "choose an empty folder (or --force to replace everything)"
        )


def init_bundle(
    out_dir: Path,
    keys: Keys,
    consumers: list[str],
    endpoint: str = "tls/127.0.0.1:7447",
    listen: str | None = None,
    path_root: Path | None = None,
    force: bool = False,
    vss_keys: str = VSS_KEYS,
) -> dict[str, Path]:
    """Write the CA, each role's certificate and Zenoh file; returns {role: its zenoh.json5}.

    `endpoint` is where the other roles reach the router (its host goes into the router's
    certificate); `listen` is where the router listens (default: `endpoint`). Raises
    ConfigError before writing anything for a bad name, endpoint or a non-empty folder.
    `vss_keys` is the key expression of the daemon's COVESA VSS signals (`Vehicle/**`, under
    `zenoh.vss_prefix` when one is set): only the daemon may put there.
    """
    listen = listen or endpoint
    _check(out_dir, consumers, endpoint, listen, force)
    vid = keys.vehicle_id
    names = {
        "router": [f"router.{vid}"],
        "daemon": [f"daemon.{vid}"],
        "speed": [f"speed.{vid}"],
        "consumer": [f"consumer.{name}.{vid}" for name in consumers],
    }
    authority = CertificateAuthority(f"roadgaze-ca.{vid}")
    ca = authority.issued
    _write(out_dir / "ca" / "ca.key", ca.key_pem, private=True)
    _write(out_dir / "ca" / "ca.pem", ca.cert_pem)
    dns_names, ip_addresses = _host_names(endpoint)
    roles = {"router": names["router"][0], "daemon": names["daemon"][0], "speed": names["speed"][0]}
    roles |= {f"consumer-{name}": cn for name, cn in zip(consumers, names["consumer"], strict=True)}
    written: dict[str, Path] = {}
    for role, common_name in roles.items():
        server = role == "router"
        issued: Issued = authority.issue(
            common_name,
            server=server,
            dns_names=dns_names if server else (),
            ip_addresses=ip_addresses if server else (),
        )
        folder = out_dir / role
        _write(folder / "key.pem", issued.key_pem, private=True)
        _write(folder / "cert.pem", issued.cert_pem)
        _write(folder / "ca.pem", ca.cert_pem)
        seen_as = (out_dir.resolve() if path_root is None else path_root) / role
        if server:
            config = router_config(seen_as, listen, keys, names, vss_keys)
        elif role == "daemon":
            config = daemon_config(seen_as, endpoint)
        else:
            config = client_config(seen_as, endpoint)
        _write(folder / "zenoh.json5", (json.dumps(config, indent=2) + "\n").encode())
        written[role] = folder / "zenoh.json5"
    return written
