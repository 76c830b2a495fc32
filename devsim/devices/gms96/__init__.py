"""GMS96 servo amplifier family (software v4.04): link layer, device and tables."""
