"""robonix-api's ``robonix_api.atlas``: the ``ATLAS`` singleton (see :mod:`robonix_api.atlas_client`).

``ATLAS`` is a :class:`~robonix_api.atlas_client.RobonixAtlas`: robonix-api's names, signatures and
error behaviour, plus this SDK's extras (``set_state``, ``register``, ``wait_ready``, heartbeat
recovery through ``start_heartbeat(..., on_not_found=)``).
"""

from robonix_api.atlas_client import ATLAS, AtlasClient, RobonixAtlas

_Atlas = RobonixAtlas  # robonix-api's class name

__all__ = ["ATLAS", "AtlasClient", "RobonixAtlas"]
