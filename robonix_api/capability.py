"""robonix-api's ``robonix_api.capability``: the provider classes (defined in :mod:`robonix_api.provider`)."""

from robonix_api.provider import Primitive, Service, Skill

__all__ = ["Primitive", "Service", "Skill"]
