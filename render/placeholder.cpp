namespace flexirob::render { int placeholder() { return 0; } }
