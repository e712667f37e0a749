"""The router's access control, size limits and rate limits for one vehicle (pure: dicts).

Subjects are matched by certificate common name: `daemon.ID`, `speed.ID` and `consumer.NAME.ID`.
Default deny; each role gets only what it needs (found by removing one item at a time until a
feature broke; docs/security.md):

- the daemon may put, answer queries and hold liveliness tokens under `PREFIX/**` (its alerts,
  yaw, final state, `alive`) and under `PREFIX/*/@adv/**` (the advanced publisher's cache,
  heartbeats and publisher token: `**` never matches an `@` chunk), and subscribe to the speed;
- the speed provider may only put the speed;
- consumers may only subscribe, query and watch liveliness under those keys of their vehicle;
- the COVESA VSS signals (`--vss`, bare `Vehicle/**` paths unless `zenoh.vss_prefix` is set,
  one vehicle per network as Eclipse Kuksa assumes): only the daemon may put them, consumers
  (a Kuksa provider is one) may only subscribe to them.

`ingress` is from a node into the router, `egress` from the router to a node. A peer only sends
a put when it knows a matching subscriber, so the daemon must receive the consumers'
subscriptions (`declare_subscriber` egress) as well as their queries.
"""

from __future__ import annotations

from typing import Any

from roadgaze.transport.keys import Keys
from roadgaze.transport.payloads import MESSAGE_MAX_BYTES, SPEED_MAX_BYTES

Rule = tuple[str, list[str], list[str], list[str]]
"""(rule id, message types, flows, key names among 'dms', 'adv', 'speed', 'vss')."""

PERMISSIONS: dict[str, list[Rule]] = {
    "daemon": [
        ("daemon-out", ["put", "declare_queryable", "reply", "liveliness_token"], ["ingress"],
         ["dms", "adv"]),
        ("daemon-speed-sub", ["declare_subscriber"], ["ingress"], ["speed"]),
        ("daemon-speed-in", ["put"], ["egress"], ["speed"]),
        ("daemon-routes", ["declare_subscriber", "query"], ["egress"], ["dms", "adv"]),
        ("daemon-vss", ["put"], ["ingress"], ["vss"]),
        ("daemon-vss-routes", ["declare_subscriber"], ["egress"], ["vss"]),
    ],
    "speed": [("speed-out", ["put"], ["ingress"], ["speed"])],
    "consumer": [
        ("consumer-ask",
         ["declare_subscriber", "query", "declare_liveliness_subscriber", "liveliness_query"],
         ["ingress"], ["dms", "adv"]),
        ("consumer-get", ["put", "reply", "liveliness_token"], ["egress"], ["dms", "adv"]),
        ("consumer-vss-ask", ["declare_subscriber"], ["ingress"], ["vss"]),
        ("consumer-vss-get", ["put"], ["egress"], ["vss"]),
    ],
}  # fmt: skip
STATE_QUERIES_PER_S = 20.0
"""Per client: a flooding client cannot crowd out the others' health checks."""
SPEED_PUTS_PER_S = 100.0
VSS_KEYS = "Vehicle/**"
"""The VSS signals' key expression without `zenoh.vss_prefix`."""
VSS_MAX_BYTES = 256
"""A VSS value is a short text (`true`, `57.3`)."""


def _key_exprs(keys: Keys, names: list[str], vss_keys: str) -> list[str]:
    table = {
        "dms": f"{keys.prefix}/**",
        "adv": keys.advanced,
        "speed": keys.speed or "",
        "vss": vss_keys,
    }
    return [table[name] for name in names if table[name]]


def access_control(
    keys: Keys, common_names: dict[str, list[str]], vss_keys: str = VSS_KEYS
) -> dict[str, Any]:
    """The router's `access_control` section: default deny, one subject per role; `vss_keys`
    is where the daemon's VSS signals go (`vss_key("Vehicle.**", zenoh.vss_prefix)`)."""
    rules: list[dict[str, Any]] = []
    subjects: list[dict[str, Any]] = []
    policies: list[dict[str, Any]] = []
    for role, entries in PERMISSIONS.items():
        names = common_names.get(role)
        if not names:
            continue
        subjects.append({"id": f"{role}-subject", "cert_common_names": names})
        role_rules = []
        for rule_id, messages, flows, key_names in entries:
            key_exprs = _key_exprs(keys, key_names, vss_keys)
            if not key_exprs:
                continue
            rules.append(
                {
                    "id": rule_id,
                    "permission": "allow",
                    "messages": messages,
                    "flows": flows,
                    "key_exprs": key_exprs,
                }
            )
            role_rules.append(rule_id)
        policies.append(
            {"id": f"{role}-policy", "rules": role_rules, "subjects": [f"{role}-subject"]}
        )
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def low_pass_filter(keys: Keys, vss_keys: str = VSS_KEYS) -> list[dict[str, Any]]:
    """Router-side size limits (payload and attachment, bytes): larger messages are dropped
    whatever the transport (shared memory would bypass `rx/max_message_size`)."""
    filters = [
        {
            "id": "dms-size",
            "messages": ["put", "reply", "query"],
            "flows": ["ingress"],
            "key_exprs": [f"{keys.prefix}/**"],
            "size_limit": MESSAGE_MAX_BYTES,
        },
        {
            "id": "vss-size",
            "messages": ["put"],
            "flows": ["ingress"],
            "key_exprs": [vss_keys],
            "size_limit": VSS_MAX_BYTES,
        },
    ]
    if keys.speed is not None:
        filters.insert(
            0,
            {
                "id": "speed-size",
                "messages": ["put"],
                "flows": ["ingress"],
                "key_exprs": [keys.speed],
                "size_limit": SPEED_MAX_BYTES,
            },
        )
    return filters


def downsampling(keys: Keys) -> list[dict[str, Any]]:
    """Router-side rate caps per incoming transport: state queries and speed puts."""
    caps = [
        {
            "id": "state-queries",
            "flows": ["ingress"],
            "messages": ["query"],
            "rules": [{"key_expr": keys.state, "freq": STATE_QUERIES_PER_S}],
        }
    ]
    if keys.speed is not None:
        caps.append(
            {
                "id": "speed-rate",
                "flows": ["ingress"],
                "messages": ["put"],
                "rules": [{"key_expr": keys.speed, "freq": SPEED_PUTS_PER_S}],
            }
        )
    return caps
