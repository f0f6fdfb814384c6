namespace flexirob::planning { int placeholder() { return 0; } }
