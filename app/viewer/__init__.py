"""The desktop viewer: window, menus, input, the blit; PNG files when there is no display."""
