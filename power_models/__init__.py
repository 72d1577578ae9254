"""gliderplan.power_models"""
