# Rewrite data/scan_example.csv (made by hairfit synth) as the goniometer rig writes its scans:
# headerless columns phi, polar angle from the fiber axis (90 - theta_r), counts/s with 4
# significant digits, and `?` where the detector saturates (above 600 counts/s).
#   awk -f data/scan_example.awk data/scan_example.csv > data/scan_example.txt
BEGIN {
    FS = ","
    print "# Goniometer scan, fiber #3, light fixed at theta_i = 20 deg, phi_i = 0"
    print "# columns: detector azimuth phi (deg) | detector polar angle from the fiber axis (deg) | counts/s"
    print "# '?' = detector saturated (above 600 counts/s)"
}
/^#/ || /^theta_i/ { next }
{
    v = ($5 > 600) ? "?" : sprintf("%.4g", $5)
    printf "%4d %4d %8s\n", $4, 90 - $3, v
}
