"""What ships and readies the program: the kernel warm-up, its stamp, and the job bundle."""
