"""The sky and sun models: Preetham, the solar spectrum, Hosek-Wilkie, the Lambertian ground."""
