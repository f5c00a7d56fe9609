"""What readies the program where it is installed: the kernel warm-up and its stamp."""
