namespace flexirob::learning { int placeholder() { return 0; } }
