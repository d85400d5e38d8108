"""rosbridge-v2-compatible WebSocket server with allow-lists (rosbridge_suite is not in Debian)."""
