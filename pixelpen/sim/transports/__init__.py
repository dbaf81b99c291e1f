"""The host-facing ends of simulated devices: paced serial port, pyserial's sim:// handler, pty, pyusb backend."""
