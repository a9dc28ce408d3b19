"""pinflex: flexible-link robots on Pinocchio."""

__version__ = "0.1.0"
