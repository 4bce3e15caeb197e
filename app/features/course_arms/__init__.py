"""What only some of the course's arms have: the DH skeleton drawing (``scene``), the desktop arm's drawing and
lessons, the KR210's own folders (its gripper pose, its report's slip), and the DH editor for a typed table."""
