"""The ROS 2 message definitions rld uses without a ROS installation (rosbags' typestores).

``default_typestore()``: the standard ROS 2 Humble types (std_msgs, geometry_msgs, nav_msgs,
visualization_msgs, ...) that rosbags carries, plus eufs_msgs from the ``.msg`` files shipped
in ``rld/ros/msg/`` (``shipped_types``). ``typestore_for`` decodes a bag's connection with the
definition recorded in the bag itself when it has one (a team's eufs_msgs may differ from
ours), else with the default store. rosbags is imported here only, lazily.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

__all__ = ["MSG_DIR", "shipped_types", "default_typestore", "typestore_for", "msgdef_of"]

#: The shipped message definitions: ``msg/PACKAGE/NAME.msg`` is ``PACKAGE/msg/NAME``.
MSG_DIR = Path(__file__).resolve().parent / "msg"


def shipped_types() -> dict:
    """The rosbags type definitions of every ``.msg`` file in ``MSG_DIR``."""
    from rosbags.typesys import get_types_from_msg

    types: dict = {}
    for path in sorted(MSG_DIR.glob("*/*.msg")):
        types.update(get_types_from_msg(path.read_text(), f"{path.parent.name}/msg/{path.stem}"))
    return types


@functools.lru_cache(maxsize=1)
def default_typestore() -> Any:
    """rosbags' ROS 2 Humble typestore with the shipped eufs_msgs registered."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(shipped_types())
    return store


_BY_DEFINITION: dict[tuple[str, str, str], Any] = {}


def typestore_for(msgtype: str, msgdef: str = "", fmt: str = "") -> Any:
    """A typestore that decodes ``msgtype``: from its definition ``msgdef`` as recorded in a bag
    (``fmt`` ``ros2msg`` or ``ros2idl``; rosbag2's concatenated form), else the default one.
    A definition that does not parse falls back to the default store."""
    if not msgdef or fmt not in ("ros2msg", "ros2idl"):
        return default_typestore()
    key = (msgtype, fmt, msgdef)
    if key not in _BY_DEFINITION:
        from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

        store = get_typestore(Stores.EMPTY)
        try:
            if fmt == "ros2msg":
                store.register(get_types_from_msg(msgdef, msgtype))
            else:
                sep = "=" * 80 + "\n"
                parts = msgdef.split(sep)[1:] if msgdef.startswith(f"{sep}IDL: ") else [
                    "IDL: -\n" + msgdef]
                for part in parts:
                    store.register(get_types_from_idl(part.split("\n", 1)[1]))
            if msgtype not in store.types:
                raise KeyError(msgtype)
        except Exception:  # noqa: BLE001 - any parse failure: decode with the default types
            store = default_typestore()
        _BY_DEFINITION[key] = store
    return _BY_DEFINITION[key]


def msgdef_of(store: Any, msgtype: str) -> tuple[str, str]:
    """(definition text, RIHS01 hash) of ``msgtype`` in ``store``, as a bag records them."""
    text, _ = store.generate_msgdef(msgtype, ros_version=2)
    return text, store.hash_rihs01(msgtype)
